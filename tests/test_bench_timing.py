"""The benchmarks' samples run on the trusted path: they time a phase as a solve runs it."""

import numpy as np
import pytest

import crocopy
from crocopy.bench.timing import loops_for, sample_ms


def test_samples_skip_the_checks_of_a_users_call():
    model = crocopy.ActionModelUnicycle()
    data = model.createData()
    bad_x = np.array([np.nan, 0.0, 0.0])

    def call():
        with np.errstate(invalid="ignore"):
            model.calc(data, bad_x, np.zeros(2))

    with pytest.raises(ValueError, match="x contains NaN"):
        call()
    assert loops_for(call) >= 1
    assert sample_ms(call, 3) >= 0.0
    assert np.isnan(data.cost)
    with pytest.raises(ValueError, match="x contains NaN"):
        call()
