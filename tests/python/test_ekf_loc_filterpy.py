"""ekf_loc agrees with the paper's model written on FilterPy (paper_filterpy.py): the same
states, covariances, NIS and gate decisions over 1,000 steps of wheel prediction, compass
and laser-line updates; and the batch API gives exactly the per-call results."""

import math

import numpy as np
import pytest

import ekf_loc
from paper_filterpy import PaperEKF, config, make_scenario, wrap

STEPS = 1000
X0 = (4.0, 2.5, 0.3)
P0 = np.diag([1e-3, 1e-3, 1e-3])
TOL = 1e-9


def assert_same_state(ours, theirs, step):
    x = ours.state
    assert abs(x[0] - theirs.x[0]) <= TOL and abs(x[1] - theirs.x[1]) <= TOL, step
    assert abs(wrap(x[2] - theirs.x[2])) <= TOL, step
    np.testing.assert_allclose(ours.covariance, theirs.P, rtol=0, atol=TOL, err_msg=str(step))


@pytest.mark.parametrize("gating", [False, True])
def test_filter_matches_filterpy_over_1000_steps(gating):
    wheels, compass, observed, covs, walls, counts = make_scenario(
        STEPS, lines_every=3, outlier_every=50 if gating else 0
    )
    ours = ekf_loc.Filter(X0, P0, config(), gating=gating)
    theirs = PaperEKF(X0, P0, gating=gating)
    variance = config()["compass"]["variance"]
    refused = set()
    for k in range(STEPS):
        ours.predict_wheels(*wheels[k])
        theirs.predict_wheels(*wheels[k])
        assert_same_state(ours, theirs, k)
        outcome = ours.update_compass(compass[k])
        accepted, nis = theirs.update_compass(compass[k], variance)
        assert outcome.accepted == accepted and outcome.nis == pytest.approx(nis, rel=1e-9)
        if not accepted:
            refused.add(k)
        n = counts[k]
        result = ours.update_lines(observed[k, :n], covs[k, :n], walls[k, :n])
        for j in range(n):
            accepted, nis = theirs.update_line(observed[k, j], covs[k, j], walls[k, j])
            assert result.accepted[j] == accepted
            assert result.nis[j] == pytest.approx(nis, rel=1e-9)
        assert_same_state(ours, theirs, k)
    # The run exercised what it claims: four lines every third step, nearly all fused, and
    # the gate refused the outliers when on (every 50th heading is 1 rad off) and about 1 %
    # of the others, nothing when off.
    lines = ours.counts["lines_accepted"] + ours.counts["lines_rejected"]
    assert lines == 4 * len(range(0, STEPS, 3))
    assert ours.counts["lines_accepted"] >= 0.97 * lines
    outliers = set(range(49, STEPS, 50)) if gating else set()
    assert outliers <= refused and len(refused - outliers) <= 0.03 * STEPS
    assert ours.counts["compass_rejected"] == len(refused)
    # The filter did not simply stay where it started.
    assert math.dist(ours.state[:2], X0[:2]) > 0.5


def test_batch_equals_calls_bitwise():
    wheels, compass, observed, covs, walls, counts = make_scenario(
        300, lines_every=2, outlier_every=40
    )
    mask = np.arange(300) % 3 != 1
    one = ekf_loc.Filter(X0, P0, config())
    states, nis = [], []
    for k in range(300):
        one.predict_wheels(*wheels[k])
        nis.append(one.update_compass(compass[k]).nis if mask[k] else math.nan)
        n = counts[k]
        one.update_lines(observed[k, :n], covs[k, :n], walls[k, :n])
        states.append(one.state)
    # Unused slots may hold anything, even NaN: they are never read.
    compass = np.where(mask, compass, np.nan)
    observed = observed.copy()
    observed[counts == 0] = np.nan
    batch = ekf_loc.Filter(X0, P0, config())
    result = batch.run(
        wheels=wheels, compass=compass, compass_mask=mask, line_observed=observed,
        line_covariances=covs, line_map=walls, line_counts=counts,
    )
    assert np.array_equal(result.states, np.array(states))
    assert np.array_equal(result.states[-1], one.state)
    assert np.array_equal(result.covariances[-1], one.covariance)
    assert np.array_equal(result.compass_nis, np.array(nis), equal_nan=True)
    assert result.compass_accepted.sum() == one.counts["compass_accepted"]
    assert np.isnan(result.line_nis[counts == 0]).all()
    assert result.line_accepted.sum() == one.counts["lines_accepted"]
    assert batch.counts == one.counts
