"""Seeds derived from the study seed and a name, never from the order of a loop.

Hashing (study seed, replica, experiment name) means adding a month or a speed to a study
leaves the seeds, and so the numbers, of every other experiment unchanged; and two noise
levels of the same replica share the random draws (common random numbers), so their
difference shows the noise level, not the luck of the draw.
"""

from __future__ import annotations

import hashlib

SEED_BITS = 31  # fits every consumer: numpy, FMPy, C int


def derive_seed(study_seed: int, *parts: object) -> int:
    """A non-negative 31-bit seed determined only by the study seed and ``parts``."""
    text = "\x1f".join([str(int(study_seed)), *(str(part) for part in parts)])
    digest = hashlib.sha256(text.encode("utf-8")).digest()
    return int.from_bytes(digest[:8], "big") % (1 << SEED_BITS)
