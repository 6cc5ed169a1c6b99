"""ekf_loc agrees with the paper's model written on FilterPy (paper_filterpy.py): the same
states, covariances, NIS and gate decisions over 1,000 steps of wheel prediction, compass
and laser-line updates, and the same innovations y, S and gains K; the batch API gives
exactly the per-call results; copies and pickles of a filter continue bit for bit."""

import copy
import math
import pickle

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


def test_update_outcomes_carry_filterpys_y_s_and_k():
    """Each compass and line update hands back FilterPy's y, S and K for the same update;
    a refused update its y and S, and K zeros (nothing applied, where FilterPy's K is the
    gain it computed before the gate undid the update)."""
    steps = 120
    wheels, compass, observed, covs, walls, _ = make_scenario(steps, outlier_every=40)
    # Every 30th step, line 0 is 0.5 m off: the line gate refuses it.
    observed[29::30, 0, 0] += 0.5
    ours = ekf_loc.Filter(X0, P0, config())
    theirs = PaperEKF(X0, P0)
    variance = config()["compass"]["variance"]
    refused = {"compass": [], "lines": []}

    def check(y, s, k, accepted, before, after):
        # Round-off apart (FilterPy inverts S with numpy, ekf-core in closed form).
        assert y.shape == theirs.y.shape and s.shape == theirs.S.shape
        assert k.shape == theirs.K.shape
        np.testing.assert_allclose(y, theirs.y, rtol=0, atol=1e-14)
        np.testing.assert_allclose(s, theirs.S, rtol=0, atol=1e-14 * np.abs(s).max())
        if accepted:
            np.testing.assert_allclose(k, theirs.K, rtol=0, atol=1e-14 * np.abs(k).max())
            # What was applied: x+ = x- + K y (theta wrapped).
            step = after - before
            step[2] = wrap(step[2])
            np.testing.assert_allclose(step, k @ y, rtol=0, atol=1e-14)
        else:
            assert np.array_equal(k, np.zeros(k.shape))
            assert np.array_equal(after, before)

    for k in range(steps):
        ours.predict_wheels(*wheels[k])
        theirs.predict_wheels(*wheels[k])
        before = ours.state
        outcome = ours.update_compass(compass[k])
        accepted, _ = theirs.update_compass(compass[k], variance)
        assert outcome.accepted == accepted
        check(outcome.y, outcome.S, outcome.K, accepted, before, ours.state)
        if not accepted:
            refused["compass"].append(k)
        # One line at a time, so that the state before each is at hand.
        for j in range(len(walls[k])):
            before = ours.state
            result = ours.update_lines(observed[k, j:j + 1], covs[k, j:j + 1], walls[k, j:j + 1])
            accepted, _ = theirs.update_line(observed[k, j], covs[k, j], walls[k, j])
            assert result.accepted[0] == accepted
            assert result.y.shape == (1, 2) and result.S.shape == (1, 2, 2)
            assert result.K.shape == (1, 3, 2)
            check(result.y[0], result.S[0], result.K[0], accepted, before, ours.state)
            if not accepted:
                refused["lines"].append((k, j))
        assert_same_state(ours, theirs, k)
    # Refused: the 1-rad compass outliers, the lines moved 0.5 m and one ordinary line (the
    # 99 % gate refuses about 1 % of consistent lines), by both filters alike.
    assert refused["compass"] == [39, 79, 119]
    assert refused["lines"] == [(22, 2), (29, 0), (59, 0), (89, 0), (119, 0)]


def test_line_updates_report_y_s_and_k_per_line_as_fused_in_sequence():
    """update_lines with N lines gives, line by line, what N one-line calls give."""
    wheels, _, observed, covs, walls, _ = make_scenario(5)
    observed[4, 2, 0] += 0.5  # refused
    together = ekf_loc.Filter(X0, P0, config())
    apart = ekf_loc.Filter(X0, P0, config())
    for k in range(5):
        together.predict_wheels(*wheels[k])
        apart.predict_wheels(*wheels[k])
        result = together.update_lines(observed[k], covs[k], walls[k])
        assert result.y.shape == (4, 2) and result.S.shape == (4, 2, 2)
        assert result.K.shape == (4, 3, 2)
        for j in range(4):
            one = apart.update_lines(observed[k, j:j + 1], covs[k, j:j + 1], walls[k, j:j + 1])
            assert one.accepted[0] == result.accepted[j]
            assert np.array_equal(one.y[0], result.y[j])
            assert np.array_equal(one.S[0], result.S[j])
            assert np.array_equal(one.K[0], result.K[j])
        assert np.array_equal(together.state, apart.state)
    assert result.accepted.tolist() == [True, True, False, True]
    assert np.array_equal(result.K[2], np.zeros((3, 2)))
    # The refused line's innovation in r is the 0.5 m it was moved, give or take its noise.
    assert abs(result.y[2, 0] - 0.5) < 0.1


DUPLICATES = {
    "copy.copy": copy.copy,
    "copy.deepcopy": copy.deepcopy,
    "pickle": lambda f: pickle.loads(pickle.dumps(f)),
    "pickle protocol 0": lambda f: pickle.loads(pickle.dumps(f, protocol=0)),
}


def same_bits(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


@pytest.mark.parametrize("gating", [True, False])
@pytest.mark.parametrize("how", list(DUPLICATES))
def test_copies_and_pickles_are_independent_and_continue_bit_for_bit(how, gating):
    steps = 200
    wheels, compass, observed, covs, walls, counts = make_scenario(
        steps, lines_every=2, outlier_every=25
    )

    def step(f, k):
        """One step of every kind; everything it returns and leaves in the filter."""
        f.predict_wheels(*wheels[k])
        c = f.update_compass(compass[k])
        n = counts[k]
        lines = f.update_lines(observed[k, :n], covs[k, :n], walls[k, :n])
        f.predict_odometry(0.01, 0.002)
        return [f.state, f.covariance, c.nis, c.accepted, c.y, c.S, c.K,
                lines.nis, lines.accepted, lines.y, lines.S, lines.K]

    # config() is not the default config (laser mount, compass variance, gates): a copy
    # that fell back to the defaults would not continue as the original does.
    original = ekf_loc.Filter(X0, P0, config(), gating=gating)
    for k in range(steps // 2):
        step(original, k)
    duplicate = DUPLICATES[how](original)
    assert type(duplicate) is ekf_loc.Filter and duplicate is not original
    assert duplicate.__getstate__() == original.__getstate__()
    assert duplicate.counts == original.counts
    for k in range(steps // 2, steps):
        ours, theirs = step(original, k), step(duplicate, k)
        assert all(same_bits(a, b) for a, b in zip(ours, theirs)), k
    assert duplicate.counts == original.counts
    # Outliers refused with the gates on, fused with them off.
    assert (original.counts["compass_rejected"] >= steps // 25) == gating
    # Independent: changing one leaves the other as it was, both ways.
    saved = duplicate.__getstate__()
    original.state = (0.0, 0.0, 0.0)
    original.covariance = np.eye(3)
    original.predict_wheels(1.0, 1.0, 0.1)
    assert duplicate.__getstate__() == saved
    saved = original.__getstate__()
    step(duplicate, 0)
    assert original.__getstate__() == saved
