"""The hand interface and the policy runner on the kinematic simulator."""

import csv
import dataclasses
import math

import numpy as np
import pytest

from crmgrasp import SensorNoise, make_task
from crmgrasp.agents import GreedyPolicy, train_trials
from crmgrasp.hardware.contact_sensing import NoContact
from crmgrasp.hardware.runner import HandInterface, KinematicHand, PolicyRunner


@pytest.fixture(scope="module")
def policy():
    task = make_task("paper-box")
    res = train_trials(task, "sarsa", trials=3, episodes=2000, seed=0, eval_episodes=200)
    best = int(np.argmin(res.greedy_steps.mean(axis=1)))
    return GreedyPolicy.from_agent(task, 2, res.agents[best])


def test_kinematic_hand_implements_the_interface(policy):
    task = policy.task
    hand = KinematicHand(task, task.sample_start(np.random.default_rng(0)), np.random.default_rng(1))
    assert isinstance(hand, HandInterface)


def test_runner_grasps_and_logs(policy, tmp_path):
    task = policy.task
    far = task.hand.contact(task.obj, (-0.15, -0.02), (-0.01, -0.05))
    hand = KinematicHand(task, far, np.random.default_rng(0))
    res = PolicyRunner(policy).run(hand, np.random.default_rng(0), log=tmp_path / "run.csv")
    assert res.grasped and res.crms == 2 and res.stopped == "grasp sensed"
    with open(tmp_path / "run.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["crm"] for r in rows] == ["(b,b,-0.08)", "(a,b,0)", ""]
    assert rows[0]["error"] == "none" and float(rows[-1]["rho"]) == pytest.approx(0.0)


def test_runner_under_noise(policy):
    task = policy.task
    tolerant = dataclasses.replace(task.hand, palm_normal_tol=math.sin(math.radians(10)))
    noisy = dataclasses.replace(task, hand=tolerant, mu_goal=0.15)
    runner = PolicyRunner(policy, task=noisy)
    rng = np.random.default_rng(3)
    results = [
        runner.run(KinematicHand(noisy, noisy.sample_start(rng), rng, SensorNoise(math.radians(3), 0.002)), rng)
        for _ in range(50)
    ]
    assert sum(r.grasped for r in results) >= 47


def test_runner_refuses_an_incompatible_task(policy):
    from crmgrasp import CRM, CrmgraspError

    other = dataclasses.replace(policy.task, actions=(CRM("a", "b", 0.0),), symmetry=None)
    with pytest.raises(CrmgraspError, match="other CRMs or bins"):
        PolicyRunner(policy, task=other)


def test_runner_stops_without_contact(policy):
    class Lost:
        def sense(self):
            return NoContact("force 0 N below the 0.05 N contact threshold")

        def execute(self, crm):
            raise AssertionError("must not move without contact")

    res = PolicyRunner(policy).run(Lost(), np.random.default_rng(0))
    assert not res.grasped and res.crms == 0 and res.stopped.startswith("no contact")
    assert res.readings == []  # nothing sensed: nothing for --figure to draw but the message


def test_readings_figure_draws_every_reading_or_says_none_was_sensed(policy):
    from crmgrasp.plotting.readings import readings_figure

    task = policy.task
    start = task.hand.contact(task.obj, a=(-0.15, -0.02), b=(-0.01, -0.05))
    res = PolicyRunner(policy).run(KinematicHand(task, start, np.random.default_rng(0)), np.random.default_rng(0))
    panels = [(config, f"{crm} -> {error}") for config, crm, error in res.readings]
    fig = readings_figure(task.obj, task.hand, panels, "a run")
    titles = [ax.get_title() for ax in fig.axes]
    assert titles == [text for _, text in panels] and fig.get_suptitle() == "a run"
    assert len({(ax.get_xlim(), ax.get_ylim()) for ax in fig.axes}) == 1  # one scale for every panel
    empty = readings_figure(task.obj, task.hand, [], "lost")
    assert [t.get_text() for t in empty.axes[0].texts] == ["no contact sensed"]
