"""Explicit POMDPs: belief update, PBVI, Cassandra files, and the sampled task model."""

import numpy as np
import pytest
from scipy import sparse

from crmgrasp import CrmgraspError
from crmgrasp.planners.pomdp import POMDP, belief_update, collect_beliefs, read_cassandra, solve_pbvi, write_cassandra
from crmgrasp.planners.pomdp_task import POMDPAgent, build_task_pomdp
from crmgrasp.planners.references import sample_starts


def aliased():
    """States L, R (aliased: both observe 0) and goal G (observes 2). Action 0 grasps
    from L, else errs (observes 1) and stays; action 1 grasps from R. Optimum: 1.5."""
    t0 = sparse.csr_matrix(np.array([[0, 0, 1], [0, 1, 0], [0, 0, 1]], dtype=float))
    t1 = sparse.csr_matrix(np.array([[1, 0, 0], [0, 0, 1], [0, 0, 1]], dtype=float))
    z = np.zeros((2, 3, 3))
    z[0] = [[0, 1, 0], [0, 1, 0], [0, 0, 1]]  # after action 0, a non-goal state reports the error
    z[1] = [[0, 1, 0], [0, 1, 0], [0, 0, 1]]
    return POMDP(3, 2, 3, [t0, t1], z, np.array([0.5, 0.5, 0.0]), np.array([False, False, True]), goal_obs=2)


def test_belief_update_by_hand():
    m = aliased()
    # b0 = (1/2, 1/2, 0); action 0; error observed: only R is consistent
    assert belief_update(m, m.b0, 0, 1).tolist() == [0.0, 1.0, 0.0]
    assert belief_update(m, m.b0, 0, 2).tolist() == [0.0, 0.0, 1.0]
    assert belief_update(m, m.b0, 0, 0) is None  # impossible observation


def test_pbvi_solves_the_aliased_task():
    m = aliased()
    beliefs = collect_beliefs(m, 10, 3, np.random.default_rng(0))
    policy = solve_pbvi(m, beliefs, horizon=3)
    assert -policy.value(m.b0, 3) == pytest.approx(1.5)
    assert -policy.value(np.array([1.0, 0.0, 0.0]), 3) == pytest.approx(1.0)
    assert policy.action(np.array([0.0, 1.0, 0.0]), 3) == 1


def test_cassandra_roundtrip(tmp_path):
    m = aliased()
    path = write_cassandra(m, tmp_path / "aliased.pomdp")
    text = path.read_text()
    assert "states: 3" in text and "T: 0 : 0 : 2 1.0" in text
    back = read_cassandra(path)
    assert (back.n_states, back.n_actions, back.n_obs) == (3, 2, 3)
    np.testing.assert_array_equal(back.b0, m.b0)
    np.testing.assert_array_equal(back.goal, m.goal)
    np.testing.assert_array_equal(back.Z, m.Z)
    for a in range(2):
        np.testing.assert_array_equal(back.T[a].toarray(), m.T[a].toarray())
    (tmp_path / "bad.pomdp").write_text("states: x\n")
    with pytest.raises(CrmgraspError, match="cannot read POMDP file"):
        read_cassandra(tmp_path / "bad.pomdp")


@pytest.mark.parametrize("cell", [0.0, -0.01, float("nan"), float("inf"), 1e-320, 1e-9])
def test_a_cell_size_that_is_not_a_size_is_one_line(task, cell):
    """A cell below the POMDP's state bound per edge (1e-320 m overflowed the cell count to
    infinity: OverflowError), zero, negative or not finite: refused before any sampling."""
    with pytest.raises(CrmgraspError, match="cell") as info:
        build_task_pomdp(task, cell=cell, samples=10, n_starts=50, seed=0)
    assert "\n" not in str(info.value)


def test_sampled_paper_box_pomdp(task, tmp_path):
    tp = build_task_pomdp(task, cell=0.02, samples=10, n_starts=500, seed=0)
    m = tp.model
    assert m.counts["states"] == m.n_states and m.counts["crm_samples"] > 0
    for a in range(m.n_actions):  # rows of T and Z are distributions
        np.testing.assert_allclose(np.asarray(m.T[a].sum(axis=1)).ravel(), 1.0)
        np.testing.assert_allclose(m.Z[a].sum(axis=1), 1.0)
    agent = POMDPAgent(tp, n_beliefs=100)
    runs = [agent.run(c) for c in sample_starts(task, 400, seed=3)]
    assert all(ok for _, ok in runs) and np.mean([n for n, _ in runs]) < 1.75
    assert 1.3 < agent.model_value() < 2.2
    back = read_cassandra(write_cassandra(m, tmp_path / "box.pomdp"))
    assert back.n_states == m.n_states


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (("states: 3", "states: -2"), r"states must be an integer in \[1, 100000000\], got -2"),
        (("states: 3", "states: 10000000000"), "states must be an integer"),
        (("observations: 3", "observations: 100000000"), "exceed 100,000,000 entries"),
        (("T: 0 : 0 : 2 1.0", "T: 0 : 0 : 9 1.0"), "entry 'T: 0 : 0 : 9 1.0' is out of range"),
        (("T: 0 : 0 : 2 1.0", "T: 0 : 0 : 2 nan"), "entry 'T: 0 : 0 : 2 nan' is out of range"),
        (("O: 0 : 0 : 1 1.0", "O: 0 : 0 : 7 1.0"), "entry 'O: 0 : 0 : 7 1.0' is out of range"),
        (("O: 0 : 0 : 1 1.0", "O: 0 : 0 : 1 1.5"), "is out of range"),
        (("R: * : 2 : * : * 0.0", "R: * : 5 : * : * 0.0"), "a reward names a state outside 0..2"),
        (("R: * : 2 : * : * 0.0", "R: * : 2"), "cannot read POMDP file"),
        (("T: 0 : 0 : 2 1.0", "T: 0 : 0"), "cannot read POMDP file"),
    ],
)
def test_a_corrupt_pomdp_file_is_one_line_naming_it(tmp_path, edit, message):
    """Sizes, indices and probabilities are checked before anything is built (a negative or
    huge size, an index out of range, a NaN reached numpy and scipy as a traceback or a
    74 GB allocation)."""
    text = write_cassandra(aliased(), tmp_path / "m.pomdp").read_text()
    assert edit[0] in text
    bad = tmp_path / "bad.pomdp"
    bad.write_text(text.replace(edit[0], edit[1], 1))
    with pytest.raises(CrmgraspError, match=message) as err:
        read_cassandra(bad)
    assert "\n" not in str(err.value) and "bad.pomdp" in str(err.value)


def test_pbvi_and_belief_collection_check_their_arguments():
    m = aliased()
    for beliefs, message in [
        (np.full((2, 2), 0.5), r"beliefs must be rows of 3 non-negative numbers"),
        ([[0.5, 0.5, np.nan]], "beliefs must be rows"),
        ([[0.5, 0.6, 0.0]], "each row sums to 1"),
        ("x", "beliefs must be rows"),
    ]:
        with pytest.raises(CrmgraspError, match=message):
            solve_pbvi(m, beliefs, 3)
    with pytest.raises(CrmgraspError, match=r"horizon must be an integer in \[0, 1000\], got 1001"):
        solve_pbvi(m, m.b0[None], 1001)
    with pytest.raises(CrmgraspError, match="solve_pbvi needs a POMDP, got None"):
        solve_pbvi(None, m.b0[None], 3)
    with pytest.raises(CrmgraspError, match=r"rng must be a numpy\.random\.Generator"):
        collect_beliefs(m, 3, 2, 0)
    with pytest.raises(CrmgraspError, match=r"number of beliefs must be an integer in \[1, 100000\]"):
        collect_beliefs(m, 10**100, 2, np.random.default_rng(0))
