"""Error and warning types of the selection pipeline.

``SelectionError`` is both a ``SpindlebenchError`` (the CLI prints it as one line) and a
``ValueError`` (scikit-learn's estimator checks expect bad input to raise ``ValueError``).
"""

from spindlebench.errors import SpindlebenchError


class SelectionError(SpindlebenchError, ValueError):
    """Input the selection method cannot work with, phrased as one line."""


class SelectionWarning(UserWarning):
    """Input the method handles in a documented way that changes the result (e.g. a
    constant sensor dropped, or ties making the requested cluster count impossible)."""


class SelectionOverflowError(SelectionError):
    """Finite input so large that a sum of squares or a product overflows float64: the
    result would be inf or NaN (or, worse, silently zero correlations), so it is refused.
    ``evaluate`` adds the recording's name."""
