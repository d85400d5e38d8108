"""rbd_local.compat: Python 3.10's zip(strict=True) for Python 3.9."""

import numpy as np
import pytest

from rbd_local.compat import zip_strict


def test_equal_lengths_zip_as_zip_does():
    assert list(zip_strict([1, 2], np.array([3, 4]), "ab")) == [(1, 3, "a"), (2, 4, "b")]


def test_different_lengths_raise_before_anything_is_yielded():
    with pytest.raises(ValueError, match="different lengths"):
        zip_strict([1, 2, 3], [1, 2])
