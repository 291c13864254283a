"""``random_state`` as scikit-learn takes it (None, an int, a ``RandomState``), and a NumPy
``Generator`` too, without ever touching NumPy's global generator.

Why: a seeded method must be reproducible from the seed a command records, a caller holding a
``Generator`` must be able to pass it, and fitting a method must not reseed the global
generator under the caller's feet (scikit-fuzzy's ``cmeans(seed=...)`` calls
``np.random.seed``; ``fcm_init`` builds its start instead, the same numbers).

An int keeps exactly the numbers the methods drew before ``Generator``s were accepted; None
draws fresh entropy (not reproducible, as in scikit-learn); a ``Generator`` or ``RandomState``
is advanced by the draw of one 32-bit seed.
"""

from __future__ import annotations

from numbers import Integral

import numpy as np

#: The ``_parameter_constraints`` entry of a ``random_state``.
RANDOM_STATE_CONSTRAINT: list = ["random_state", np.random.Generator]


def int_seed(random_state) -> int:
    """One 32-bit seed from ``random_state`` (the int itself when it is one)."""
    if isinstance(random_state, Integral) and not isinstance(random_state, bool):
        return int(random_state)
    if random_state is None:
        return int(np.random.default_rng().integers(2**32))
    if isinstance(random_state, np.random.Generator):
        return int(random_state.integers(2**32))
    if isinstance(random_state, np.random.RandomState):
        return int(random_state.randint(2**32, dtype=np.uint64))
    raise ValueError(f"random_state must be None, an int, a numpy Generator or RandomState, "
                     f"got {random_state!r}")


def as_generator(random_state) -> np.random.Generator:
    """A ``Generator``: the one given, else seeded by ``int_seed`` (an int seeds it as
    ``np.random.default_rng(int)`` does)."""
    if isinstance(random_state, np.random.Generator):
        return random_state
    return np.random.default_rng(int_seed(random_state))


def fcm_init(n_clusters: int, n_points: int, random_state) -> np.ndarray:
    """The start memberships ``cmeans(seed=s)`` draws (``np.random.seed(s)``, ``rand``,
    columns normalised), from a private ``RandomState``: the same numbers for an int seed,
    and the global generator is left alone."""
    u0 = np.random.RandomState(int_seed(random_state)).rand(n_clusters, n_points)
    return u0 / np.ones((n_clusters, 1)).dot(np.atleast_2d(u0.sum(axis=0)))
