"""Discrete elastica: bad input.  The statements (Def 3.2, Thm 3.8, Cor 3.9, Remark 3.7, the smooth
limits) are `ddgjax verify` checks (`sec3_elastica`, run by `test_verify_checks.py`)."""

import numpy as np
import pytest

from ddgjax.errors import InvalidInputError, NonFiniteError
from energies import elastica


def test_bad_input():
    with pytest.raises(elastica.InfeasibleChordError, match="not shorter than the length"):
        elastica.clamped(10, length=1.0, chord=[1.2, 0, 0], t_start=[1, 0, 0], t_end=[1, 0, 0])
    T = np.tile([1.0, 0.0, 0.0], (10, 1))
    T[4, 1] = np.nan
    with pytest.raises(NonFiniteError, match=r"index \(4, 1\)"):
        elastica.clamped(10, chord=[0.5, 0, 0], t_start=[0, 1, 0], t_end=[0, -1, 0], x0=T)
    with pytest.raises(InvalidInputError, match="clamp"):
        elastica.clamped(10, chord=[0.5, 0, 0], t_start=[0, 1, 0], t_end=[0, -1, 0], clamp="free")
    with pytest.raises(InvalidInputError, match="t_start"):
        elastica.clamped(10, chord=[0.5, 0, 0], t_start=[0, 0, 0], t_end=[0, -1, 0])
