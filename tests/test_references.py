"""Clairvoyant bound and exact belief-space optimum on sampled starts."""

import itertools

import numpy as np
import pytest

from crmgrasp import CRM, Config, Contact, CrmgraspError, Disc, Hand, Task, make_task
from crmgrasp.agents import make_agent
from crmgrasp.agents.training import encoder_for, rollout
from crmgrasp.planners.references import belief_optimum, clairvoyant_bound, clairvoyant_steps, sample_starts
from crmgrasp.tasks import UniformStarts


def test_aliased_pair_by_hand(task):
    # the two mirror near-corner starts observe the same thing; one opposition works in each
    a = task.hand.contact(task.obj, (-0.15, -0.02), (-0.10, -0.05))
    b = task.hand.contact(task.obj, (0.10, -0.05), (0.15, -0.02))
    assert task.discretizer.index(__import__("crmgrasp").observe(a), 0) == task.discretizer.index(
        __import__("crmgrasp").observe(b), 0
    )
    assert clairvoyant_steps(task, a) == 1 and clairvoyant_steps(task, b) == 1
    assert clairvoyant_bound(task, [a, b]) == 1.0
    assert belief_optimum(task, [a, b]) == 1.5  # guess one opposition; on failure, the other


def test_far_start_needs_two(task):
    far = task.hand.contact(task.obj, (-0.15, -0.02), (-0.01, -0.05))
    assert clairvoyant_steps(task, far) == 2
    assert belief_optimum(task, [far]) == 2.0


def test_one_crm_always_suffices_on_a_disc():
    disc = Task("disc", Disc(0.04), Hand(0.16, 0.12), (CRM("a", "b", 0.0), CRM("a", "a", 0.02)), starts=UniformStarts())
    starts = sample_starts(disc, 100, seed=0)
    assert clairvoyant_bound(disc, starts) == 1.0
    assert belief_optimum(disc, starts) == 1.0


@pytest.mark.parametrize("agent", ["fixed", "random"])
def test_no_policy_beats_the_optimum_on_its_starts(task, agent):
    starts = sample_starts(task, 300, seed=1)
    opt, clair = belief_optimum(task, starts), clairvoyant_bound(task, starts)
    assert clair <= opt
    policy = make_agent(agent, len(task.actions))
    enc = encoder_for(task, 2)
    rng = np.random.default_rng(0)
    mean = np.mean([len(rollout(task, policy, enc, s, rng)[0]) for s in starts])
    assert mean >= opt


def test_paper_box_references_match_spec(task):
    starts = sample_starts(task, 4000, seed=0)
    assert clairvoyant_bound(task, starts) == pytest.approx(1.19, abs=0.02)
    assert belief_optimum(task, starts) == pytest.approx(1.66, abs=0.02)


def test_bad_reference_input(task):
    with pytest.raises(CrmgraspError, match="belief_optimum needs a non-empty list of starts"):
        belief_optimum(task, [])
    with pytest.raises(CrmgraspError, match=r"number of starts must be an integer in \[1, 1000000\], got 0"):
        sample_starts(make_task("paper-box"), 0, seed=0)
    with pytest.raises(CrmgraspError, match=r"seed must be an integer in \[0, 9223372036854775807\], got -1"):
        sample_starts(task, 3, seed=-1)
    with pytest.raises(
        CrmgraspError, match=r"belief_optimum needs a Task \(crmgrasp.make_task\(name\)\), got 'paper-box'"
    ):
        belief_optimum("paper-box", [])
    with pytest.raises(CrmgraspError, match=r"clairvoyant_bound needs a non-empty list of starts .*, got 3"):
        clairvoyant_bound(task, 3)
    assert clairvoyant_steps(task, Config(Contact(-0.15, 0.0, 1.0, 0.0), Contact(0.15, 0.0, -1.0, 0.0))) >= 1
    starts = sample_starts(task, 5, seed=0)
    for horizon in (-1, 0, 1.5, 1001):  # -1 gave a mean of -1.0 CRMs, 0 the task's step limit
        with pytest.raises(CrmgraspError, match=r"horizon must be an integer in \[1, 1000\]"):
            belief_optimum(task, starts, horizon=horizon)
        with pytest.raises(CrmgraspError, match="horizon must be"):
            clairvoyant_bound(task, starts, horizon=horizon)
    assert belief_optimum(task, starts, horizon=task.max_steps) == belief_optimum(task, starts)
    with pytest.raises(CrmgraspError, match="start must be a Config of two Contacts, got 'x'"):
        clairvoyant_steps(task, "x")  # type: ignore[arg-type]
    off = Config(Contact(-0.5, 0.0, 1.0, 0.0), Contact(0.15, 0.0, -1.0, 0.0))
    with pytest.raises(CrmgraspError, match=r"start: contact a at \(-0.5, 0\) is 0.35 m off the object"):
        belief_optimum(task, [*starts, off])


def test_belief_policy_executes_its_own_value(task):
    from crmgrasp.planners.references import BeliefPolicy

    starts = sample_starts(task, 300, seed=4)
    policy = BeliefPolicy(task, starts)
    executed = [policy.run(c) for c in starts]
    assert np.mean([n for n, _ in executed]) == pytest.approx(belief_optimum(task, starts), abs=1e-12)
    fresh = [policy.run(c) for c in sample_starts(task, 300, seed=5)]
    assert all(ok for _, ok in fresh) and 1.3 < np.mean([n for n, _ in fresh]) < 2.0


def test_belief_policy_told_another_policys_action(task):
    """A handover (benchmarks/handover.py): after a CRM the policy did not choose, told which
    one was taken, the belief still holds the true start, so the policy grasps every start
    it plans over; a CRM index the task does not have is a one-line error."""
    from crmgrasp.planners.references import BeliefPolicy
    from crmgrasp.sim import run_episode

    class FirstForced:
        def __init__(self, inner: BeliefPolicy, first: int) -> None:
            self.inner, self.first, self.n = inner, first, 0

        def begin(self, percept):
            self.inner.begin(percept)
            self.n = 0

        def act(self):
            own = self.inner.act()
            self.a = self.first if self.n == 0 else own
            self.n += 1
            return self.a

        def tell(self, percept):
            self.inner.tell(percept, action=self.a)

    starts = sample_starts(task, 40, seed=4)
    policy = BeliefPolicy(task, starts)
    rng = np.random.default_rng(0)
    for forced in range(len(task.actions)):
        episodes = [run_episode(task, FirstForced(policy, forced), rng, start=c) for c in starts]
        assert all(ep.success for ep in episodes)
        assert any(ep.steps > 1 for ep in episodes)
    with pytest.raises(CrmgraspError, match="action"):
        policy.tell(None, action=len(task.actions))  # type: ignore[arg-type]


def test_the_optimum_over_more_worlds_is_never_lower():
    """Why the optimum over sampled worlds is optimistic (benchmarks/reference_bias.py): over
    one world it is that world's clairvoyant number, and over a union of disjoint sets it is
    at least the size-weighted mean of the sets' optima (a policy for the union is a policy
    for each set), so the mean over blocks rises as the blocks grow."""
    family = make_task("u-handle")
    worlds = sample_starts(family, 24, 3)
    singles = [belief_optimum(family, [w]) for w in worlds]
    assert singles == [clairvoyant_steps(family, w) for w in worlds]
    means = [np.mean([belief_optimum(family, worlds[i : i + n]) for i in range(0, 24, n)]) for n in (1, 3, 6, 12, 24)]
    assert all(a <= b + 1e-12 for a, b in itertools.pairwise(means))
    assert means[-1] > means[0]  # aliasing costs on this family: the bound is strict here


def test_the_nearest_fallback_keeps_the_worlds_that_explain_the_most():
    """With ``fallback="nearest"`` the policy acts as the default on the worlds it plans over
    (their own world never leaves the belief). On fresh worlds, after the reset and after
    every CRM, its belief is exactly the planned worlds that, replayed along the CRMs taken,
    mismatch the fewest observations, a world whose own episode grasped dropping out (checked
    against that replay, written out here); beliefs beyond the consistent worlds occur. An
    unknown fallback is a one-line error."""
    from crmgrasp.model.sensing import Error
    from crmgrasp.planners.references import BeliefPolicy
    from crmgrasp.sim import run_episode

    task = make_task("polygon-family")
    planned = sample_starts(task, 60, seed=1)
    default, near = BeliefPolicy(task, planned), BeliefPolicy(task, planned, fallback="nearest")
    assert [default.run(w) for w in planned] == [near.run(w) for w in planned]
    model = near._model

    def expected(actions: list[int], seen: list[int]) -> tuple[set, int]:
        alive = []
        for w in planned:
            st = model.state(w)
            i, config = model.places[st]
            miss = int(task.discretizer.index(model.tasks[i].observe(config), Error.NONE) != seen[0])
            for a, o in zip(actions, seen[1:]):
                st, o2, grasped = model.step(st, a)
                if grasped:
                    break
                miss += o2 != o
            else:
                alive.append((st, miss))
        least = min(m for _, m in alive)
        return {st for st, m in alive if m == least}, least

    class Watched:
        def __init__(self) -> None:
            self.beyond = 0

        def begin(self, percept):
            near.begin(percept)
            self.actions, self.seen = [], [percept.obs_index]
            self._check()

        def act(self):
            self.actions.append(near.act())
            return self.actions[-1]

        def tell(self, percept):
            near.tell(percept)
            if not percept.terminated:
                self.seen.append(percept.obs_index)
                self._check()

        def _check(self):
            want, least = expected(self.actions, self.seen)
            assert set(near._belief) == want
            self.beyond += least > 0

    watched = Watched()
    rng = np.random.default_rng(0)
    for w in sample_starts(task, 25, seed=2):
        run_episode(task, watched, rng, start=w)
    assert watched.beyond > 0
    with pytest.raises(CrmgraspError, match="unknown fallback 'closest'"):
        BeliefPolicy(task, planned, fallback="closest")


def _noisy(name):
    from dataclasses import replace

    from crmgrasp.model.sensing import SensorNoise

    return replace(make_task(name), noise=SensorNoise(0.05, 0.002))


@pytest.mark.parametrize(
    ("make", "n"),
    [
        (lambda: make_task("paper-box"), 100),
        (lambda: _noisy("paper-box"), 60),  # the references ignore the noise on every path
        (lambda: __import__("crmgrasp.tasks.offsets", fromlist=["x"]).offset_grid(make_task("u-handle"), 5), 25),
        (lambda: make_task("triangles-3f"), 10),
        (lambda: make_task("cup-3d"), 24),
        (lambda: make_task("box-3d-3f"), 8),
        (lambda: make_task("mixed"), 30),  # discs have no compiled kernel: the readable rules on both
    ],
    ids=["paper-box", "noisy", "u-handle-grid5", "triangles-3f", "cup-3d", "box-3d-3f", "mixed"],
)
def test_the_references_are_the_same_on_every_backend(make, n):
    """The search expands states through the kernels (compiled on "auto") and gives the readable
    rules' values exactly: the optimum, the bound, the ungraspable share and a policy's episodes."""
    from crmgrasp.planners.references import BeliefPolicy, ungraspable_fraction

    task = make()
    starts = sample_starts(task, n, 3)
    values = {
        b: (
            belief_optimum(task, starts, backend=b),
            clairvoyant_bound(task, starts, backend=b),
            ungraspable_fraction(task, starts, backend=b),
            [BeliefPolicy(task, starts[: n // 2], "nearest", backend=b).run(s) for s in starts[n // 2 :]],
        )
        for b in ("auto", "reference")
    }
    assert values["auto"] == values["reference"]
    assert values["auto"][0] >= values["auto"][1] > 0.0


@pytest.mark.parametrize("name", ["paper-box", "triangles-3f", "cup-3d", "box-3d-3f", "u-handle"])
def test_a_kernels_successors_are_the_readable_steps(name):
    """``Kernel.successors``: every CRM from a configuration, as the readable step takes it
    (next configuration, bin index, error, grasp; the least friction itself where the kernel
    reports it exactly)."""
    from crmgrasp.kernels import kernel_for
    from crmgrasp.sim import SimState, step

    task = make_task(name)
    rng = np.random.default_rng(5)
    for _ in range(6):
        inst = task.instance(rng) if task.family is not None else task
        config = inst.sample_start(rng)
        for _ in range(2):  # a start, then where a CRM took it
            for friction in ("exact", "decided"):
                got = kernel_for(inst, "auto", friction).successors(config)
                assert len(got) == len(task.actions)
                for a, s in enumerate(got):
                    want = step(inst, SimState(config, config, 0), a, rng)
                    assert (s.config, s.obs_index, s.error) == (want.state.config, want.obs_index, want.error)
                    assert inst.grasped(s.min_friction) == want.terminated
                    if friction == "exact":
                        assert s.min_friction == want.min_friction
            config = got[int(rng.integers(len(got)))].config


def test_an_unknown_reference_backend_is_one_line(task):
    with pytest.raises(CrmgraspError, match="unknown backend 'gpu'"):
        belief_optimum(task, sample_starts(task, 5, 0), backend="gpu")
