"""The identified dynamic models (issue 22) as regressors on the selection protocol.

``evaluate`` (hence ``paper``, ``sweep``, ``compensate``, ``benchmark``) fits a regressor on
the selected rises of the training recording and predicts each test recording from its own
rises. A static regressor needs nothing else. The identified models of ``identification``
are dynamic: they simulate (or filter) a recording along its time axis from the speed
programme. So for the regressors of ``names.DYNAMIC_REGRESSORS`` the protocol hands over,
per recording, the recording's own driver columns in front of the selected rises:

    X = [time_s, spindle_speed_rpm, (ambient_C for network-ambient), selected rises...]

``time_s`` and the speed are what the models are driven by; the rises are read only by the
``observer`` (its measurements); ``tf1``, ``tf2`` and ``network`` use the speed alone, so
the selection in front of them does not change their prediction. Each recording is simulated
from rest at its first sample, as the rises are taken from it: a run that starts warm starts
the model cold (the observer's sensors correct that; the speed-only models cannot).
A recording without the driver column a regressor reads is one line naming it.

Examples
--------
>>> from spindlebench.core.names import DYNAMIC_REGRESSORS
>>> [driver_columns(name) for name in ("tf1", "network-ambient")]
[('time_s', 'spindle_speed_rpm'), ('time_s', 'spindle_speed_rpm', 'ambient_C')]
>>> reads_rises("observer"), reads_rises("network")
(True, False)
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

from spindlebench.core.names import DYNAMIC_REGRESSORS
from spindlebench.formats.recording import AMBIENT_COLUMN, SPEED_COLUMN, TIME_COLUMN
from spindlebench.selection.errors import SelectionError

if TYPE_CHECKING:  # NumPy only where a model is fitted: the registry is read at start-up
    import numpy as np


def is_dynamic(regressor: str) -> bool:
    """Whether ``regressor`` is one of the identified dynamic models."""
    return regressor in DYNAMIC_REGRESSORS


def driver_columns(regressor: str) -> tuple[str, ...]:
    """The recording columns a dynamic regressor reads in front of the rises."""
    if regressor == "network-ambient":
        return (TIME_COLUMN, SPEED_COLUMN, AMBIENT_COLUMN)
    return (TIME_COLUMN, SPEED_COLUMN)


def reads_rises(regressor: str) -> bool:
    """Whether the model reads the selected rises (only the observer does)."""
    return regressor == "observer"


def make_dynamic(regressor: str, random_state: int = 0):
    """The estimator of ``regressor`` (``identification.estimators``), seeded."""
    import numpy as np

    from spindlebench.identification.estimators import (
        ObserverRegressor,
        ThermalNetworkRegressor,
        TransferFunctionRegressor,
    )

    seed = int(random_state) if isinstance(random_state, (int, np.integer)) else 0
    if regressor in ("tf1", "tf2"):
        return TransferFunctionRegressor(order=int(regressor[-1]), random_state=seed)
    if regressor == "network":
        return ThermalNetworkRegressor(random_state=seed)
    if regressor == "network-ambient":
        return ThermalNetworkRegressor(ambient=True, random_state=seed)
    if regressor == "observer":
        return ObserverRegressor(random_state=seed)
    raise SelectionError(f"{regressor!r} is not a dynamic regressor "
                         f"({', '.join(DYNAMIC_REGRESSORS)})")


def check_drivers(regressor: str, name: str, columns: Sequence[str]) -> None:
    """One line naming the recording and the column when a driver column is absent."""
    for column in driver_columns(regressor):
        if column not in columns:
            raise SelectionError(
                f"recording {name}: regressor {regressor!r} reads the column '{column}' "
                f"(the speed programme and time axis of the recording), which it does not "
                f"have")


def model_inputs(regressor: str, values: Callable[[str], np.ndarray],
                 rises: np.ndarray) -> np.ndarray:
    """``X`` of a dynamic regressor: the driver columns (``values(column)``), then the
    selected rises if it reads them."""
    import numpy as np

    drivers = [np.asarray(values(column), dtype=float) for column in driver_columns(regressor)]
    parts = [*drivers, rises] if reads_rises(regressor) else drivers
    return np.column_stack(parts)
