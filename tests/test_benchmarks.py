"""Smoke run of the benchmark script (tiny sizes; no thresholds asserted)."""

import gc
import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

from crmgrasp._validation import CrmgraspError
from crmgrasp.tasks.offsets import offset_grid

BENCH = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_core.py"


def test_bench_core_smoke(capsys):
    spec = importlib.util.spec_from_file_location("bench_core", BENCH)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    res = mod.main(["--smoke"])
    assert res["execute_us"] > 0 and res["cartpole_step_us"] > 0 and res["batch_us_per_crm"] > 0
    assert '"execute_ratio_vs_cartpole_step"' in capsys.readouterr().out


def test_run_py_smoke(capsys):
    import json

    from crmgrasp.cli.main import main

    assert main(["bench", "--smoke"]) == 0
    res = json.loads(capsys.readouterr().out)
    for key in ("step_ratio_vs_cartpole", "batch_ratio_vs_cartpole_vec", "sarsa_fig7_seconds", "batch_peak_mb"):
        assert res[key] > 0
    assert (
        -1.0 < res["import_over_gymnasium_seconds"] < 10.0
    )  # a difference of two timings: its sign is noise-free only at scale
    run = BENCH.parent / "run.py"
    assert "from bench_env import main" in run.read_text()


def test_learner_seeds_smoke():
    spec = importlib.util.spec_from_file_location("learner_seeds", BENCH.parent / "learner_seeds.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    res = mod.main(episodes=20, seeds=2, only=("pooled-vi (fastest)", "psrl"))
    for task in ("paper-box", "box-family"):
        assert set(res[task]) == {"pooled-vi (fastest)", "psrl"}
        for row in res[task].values():
            assert len(row["to_5pct"]) == 2 and 0 <= row["by_20"] <= row["by_budget"] <= 2
            assert 5 <= row["median_to_5pct"] <= 21 and set(row["mean_at"]) == {5, 10, 15, 20}


def test_bench_family_smoke(monkeypatch):
    spec = importlib.util.spec_from_file_location("bench_family", BENCH.parent / "bench_family.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    calls = []
    monkeypatch.setattr(mod, "learn", lambda task, *a, **k: calls.append((task.name, k["jobs"])))
    res = mod.main(jobs=2, repeats=2)
    assert [c[0] for c in calls] == ["paper-box"] + ["paper-box", "box-family"] * 2
    assert res["family_over_paper_box"] > 0 and len(res["runs"]) == 2


def test_bench_spatial_smoke():
    spec = importlib.util.spec_from_file_location("bench_spatial", BENCH.parent / "bench_spatial.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    res = mod.main(steps=200, rounds=1, reference=True)
    assert res["box3d_step_over_cartpole"] > 0 and res["cup3d_reference_step_us"] > res["cup3d_step_us"]
    assert res["opencup3d_reference_step_us"] > res["opencup3d_step_us"] > 0


def test_journal_benchmark_smoke():
    spec = importlib.util.spec_from_file_location("bench_journal", BENCH.parent / "bench_journal.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    res = mod.main(200)
    assert res["units"] == 200 and all(r > 0 for r in res["journal_units_per_s_first_last"])


def test_bench_fingers_smoke():
    spec = importlib.util.spec_from_file_location("bench_fingers", BENCH.parent / "bench_fingers.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    res = mod.main(steps=60)
    assert res["cartpole_us"] > 0
    for backend in ("auto", "reference"):
        assert res[backend]["us_per_step_with_resets"] >= res[backend]["us_per_step_alone"] > 0


def test_bench_planning_smoke(capsys):
    spec = importlib.util.spec_from_file_location("bench_planning", BENCH.parent / "bench_planning.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    res = mod.main(["--smoke"])
    timed = {f"families {t}, 10 episodes" for t in mod.FAMILIES} | {f"optimum {t}, 20 starts" for t in mod.OPTIMA}
    shared = {f"untried families {t}, 10 episodes" for t in mod.FAMILIES}
    assert set(res) == {f"{t} k={k}" for t, k in mod.CASES} | timed | shared
    for t, k in mod.CASES:
        row = res[f"{t} k={k}"]
        assert row["plans"] > 0 and row["compiled_us"] > 0 and row["readable_us"] > 0
        assert 0.0 < row["sweeps_share"] < 1.0 and 0.0 < row["kept_share"] < 1.0
    for label in timed:
        assert res[label]["paused_s"] > 0 and res[label]["resumed_young_s"] > 0 and res[label]["not_paused_s"] > 0
    for label in shared:
        assert 0 < res[label]["shared_rebuilds_s"] <= res[label]["shared_s"]  # rounded to 0.01 s: may be equal
        assert 0 < res[label]["afresh_rebuilds_s"] <= res[label]["afresh_s"]
    assert gc.isenabled()
    assert '"compiled_over_readable"' in capsys.readouterr().out


def test_bench_continuous_smoke():
    spec = importlib.util.spec_from_file_location("bench_continuous", BENCH.parent / "bench_continuous.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    res = mod.main(steps=100, rounds=1)
    for task in mod.TASKS:
        assert res[task]["continuous_us"] > 0 and res[task]["continuous_over_discrete"] > 0


def test_deep_continuous_smoke():
    import pytest

    from crmgrasp.agents.deep import deep_available

    if not deep_available():
        pytest.skip("needs the extra: pip install 'crmgrasp[deep]'")
    spec = importlib.util.spec_from_file_location("deep_continuous", BENCH.parent / "deep_continuous.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    res = mod.main(steps=256, episodes=5)
    assert len(res) == 3 + 4 and all(0.0 <= v["success"] <= 1.0 for k, v in res.items() if isinstance(v, dict))
    res = mod.sac(episodes=4, trials=1, eval_episodes=3)
    rows = [v for v in res.values() if isinstance(v, dict)]
    assert len(rows) == 2 and all(len(r["greedy_crms"]) == 1 and 1 <= r["greedy_crms"][0] <= 10 for r in rows)


def test_offset_learning_smoke():
    spec = importlib.util.spec_from_file_location("offset_learning", BENCH.parent / "offset_learning.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    for learner in mod.ORDERS:
        res = mod.main(episodes=20, trials=1, starts=10, learner=learner, refine={"u-handle": (9, 2), "cup-3d": (3, 0)})
        for key in ("u-handle-grid9", "cup-3d-grid3"):
            assert res[key]["median"] >= res[key]["optimum"] - 1e-12
    params = {"start_level": 1, "refine_after": 1}
    res = mod.main(10, 1, 6, "refine-vi", tasks=("u-handle",), grid=5, params=params, heldout=4)
    assert res["params"] == params and list(res)[-1] == "u-handle-grid5"
    assert res["u-handle-grid5"]["heldout"] == 4 and len(res["u-handle-grid5"]["heldout_per_trial"]) == 1
    assert res["k"] == 1 and mod.main(10, 1, 6, "backoff-vi", tasks=("u-handle",), grid=3, k=2)["k"] == 2
    res = mod.main(30, 2, 6, "backoff-vi", tasks=("u-handle",), grid=0, k=2, counts=True)  # the task's own CRMs
    own = res["u-handle"]["own_counts"]  # the grid-free task keeps its name
    assert len(own) == 2 and all(o["decisions"] >= 6 and 0.0 <= o["below_5"] <= 1.0 for o in own)
    assert all(o["median"] >= 0.0 for o in own)
    assert "own_counts" not in mod.main(10, 1, 6, "backoff-vi", tasks=("u-handle",), grid=0, k=2)["u-handle"]
    with pytest.raises(SystemExit, match="--counts needs backoff-vi"):
        mod.main(10, 1, 6, "model-vi", tasks=("u-handle",), grid=0, counts=True)


def test_family_learning_smoke():
    spec = importlib.util.spec_from_file_location("family_learning", BENCH.parent / "family_learning.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    res = mod.main(episodes=20, seeds=2, n_worlds=12, tasks=("cup-family",), learners=("pooled-vi", "backoff-vi"))
    row = res["cup-family"]
    assert "k" not in res and row["pooled-vi"]["k"] == 1 and row["backoff-vi"]["k"] == mod.ORDERS["backoff-vi"]
    other = mod.main(episodes=5, seeds=1, n_worlds=4, tasks=("cup-family",), learners=("backoff-vi",), k=3)
    assert other["k"] == 3 and other["cup-family"]["backoff-vi"]["k"] == 3
    assert row["worlds"] == 12 and 0 <= row["graspable"] <= 12 and row["optimum"] >= 1.0
    learner = row["pooled-vi"]
    assert len(learner["gap_graspable"]) == 2 and 0 <= learner["seeds_within_10pct_graspable"] <= 2
    assert all(g >= -1e-9 for g in learner["gap"])  # the belief-space optimum is a lower bound on these worlds
    for f, ff in zip(learner["fails_graspable"], learner["gap_from_fails"], strict=True):
        assert 0 <= f <= row["graspable"] and ff >= 0.0 and (f > 0 or ff == 0.0)  # a lost world costs the step limit
    cap = row["graspable"] * mod.make_task("cup-family").max_steps  # errored CRMs: at most every CRM
    assert 0 <= row["optimum_errored_graspable"] <= cap and all(0 <= e <= cap for e in learner["errored_graspable"])


def test_family_learning_declares_the_spatial_mirror_where_asked():
    spec = importlib.util.spec_from_file_location("family_learning", BENCH.parent / "family_learning.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    res = mod.main(episodes=4, seeds=1, n_worlds=3, tasks=("box-3d",), learners=("pooled-vi",), mirror=True)
    assert res["mirror"] is True and len(res["box-3d"]["pooled-vi"]["gap"]) == 1


def test_mujoco_learning_smoke(capsys, monkeypatch):
    pytest.importorskip("mujoco", reason="needs the extra crmgrasp[mujoco]")
    spec = importlib.util.spec_from_file_location("mujoco_learning", BENCH.parent / "mujoco_learning.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    argv = ["mujoco_learning.py", "--task", "paper-box", "--episodes", "3", "--seeds", "1", "--score", "2"]
    monkeypatch.setattr("sys.argv", argv)
    mod.main()
    out = json.loads(capsys.readouterr().out)
    (row,) = out["tasks"]
    assert row["task"] == "paper-box" and len(row["per_seed"]) == 1 and row["episode_seconds_median"] > 0


def test_mujoco_three_fingers_smoke(capsys, monkeypatch):
    pytest.importorskip("mujoco", reason="needs the extra crmgrasp[mujoco]")
    spec = importlib.util.spec_from_file_location("mujoco_three_fingers", BENCH.parent / "mujoco_three_fingers.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    argv = ["mujoco_three_fingers.py", "--task", "cup-family-3f", "--episodes", "5", "--worlds", "2", "--seeds", "1"]
    monkeypatch.setattr("sys.argv", [*argv, "--learner", "backoff-vi", "--k", "2", "--param", "explore=1"])
    mod.main()
    out = json.loads(capsys.readouterr().out)
    assert out["learner"] == "backoff-vi" and out["k"] == 2 and out["params"] == {"explore": 1}
    (row,) = out["tasks"]["cup-family-3f"]["per_seed"]
    assert 0 <= row["mujoco_successes"] <= 2 and 0.0 <= row["kinematic_success"] <= 1.0
    assert 0 <= row["mujoco_lost_at_step_limit"] <= 2 - row["mujoco_successes"]
    assert row["kinematic_episodes"] == 5 and "mujoco_episodes" not in row


@pytest.mark.slow
def test_mujoco_three_fingers_on_the_mirror_quotient(capsys, monkeypatch):
    """``--mirror`` runs a tripod's learner on the mirror quotient (recorded in the output); a
    task whose mirror is not known to hold is a usage error."""
    pytest.importorskip("mujoco", reason="needs the extra crmgrasp[mujoco]")
    spec = importlib.util.spec_from_file_location("mujoco_three_fingers", BENCH.parent / "mujoco_three_fingers.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    argv = ["mujoco_three_fingers.py", "--episodes", "3", "--worlds", "1", "--seeds", "1", "--mirror"]
    monkeypatch.setattr("sys.argv", [*argv, "--task", "cup-3d-3f"])
    mod.main()
    out = json.loads(capsys.readouterr().out)
    assert out["mirror"] is True and len(out["tasks"]["cup-3d-3f"]["per_seed"]) == 1
    monkeypatch.setattr("sys.argv", [*argv, "--task", "open-cup-3d"])
    with pytest.raises(SystemExit) as exc:
        mod.main()
    assert exc.value.code == 2 and "open-cup-3d has no mirror symmetry known to hold" in capsys.readouterr().err


def test_mujoco_three_fingers_goes_on_learning_on_mujoco(capsys, monkeypatch):
    """``--mujoco-episodes``: the learner then learns on the stand-in (its row counts the
    episodes and the sensed grasps among them, and the scoring worlds stay the same: a second
    run with none scores another policy on them); a negative count, or one for a search, is a
    usage error."""
    pytest.importorskip("mujoco", reason="needs the extra crmgrasp[mujoco]")
    spec = importlib.util.spec_from_file_location("mujoco_three_fingers", BENCH.parent / "mujoco_three_fingers.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    argv = ["mujoco_three_fingers.py", "--task", "cup-family-3f", "--episodes", "5", "--worlds", "2", "--seeds", "1"]
    monkeypatch.setattr("sys.argv", [*argv, "--mujoco-episodes", "3", "--first-seed", "2"])
    mod.main()
    out = json.loads(capsys.readouterr().out)
    (row,) = out["tasks"]["cup-family-3f"]["per_seed"]
    assert out["mujoco_episodes"] == 3 and row["mujoco_episodes"] == 3 and row["seed"] == 2
    assert 0 <= row["mujoco_training_sensed_grasps"] <= 3 and isinstance(row["mujoco_training_faults"], dict)
    for bad in (["--mujoco-episodes", "-1"], ["--mujoco-episodes", "2", "--learner", "policy-search"]):
        monkeypatch.setattr("sys.argv", [*argv, *bad])
        with pytest.raises(SystemExit) as exc:
            mod.main()
        assert exc.value.code == 2 and "--mujoco-episodes must be at least 0" in capsys.readouterr().err


def test_mujoco_three_fingers_policy_search(capsys, monkeypatch):
    """The k-order policy search as the learner: its episodes are the ones it re-ran, its
    cost on the worlds searched is reported, and a bad number of worlds is a usage error."""
    pytest.importorskip("mujoco", reason="needs the extra crmgrasp[mujoco]")
    spec = importlib.util.spec_from_file_location("mujoco_three_fingers", BENCH.parent / "mujoco_three_fingers.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    argv = ["mujoco_three_fingers.py", "--task", "cup-family-3f", "--worlds", "2", "--seeds", "1"]
    monkeypatch.setattr("sys.argv", [*argv, "--learner", "policy-search", "--search-worlds", "6"])
    mod.main()
    out = json.loads(capsys.readouterr().out)
    assert out["learner"] == "policy-search" and out["search_worlds"] == 6
    (row,) = out["tasks"]["cup-family-3f"]["per_seed"]
    assert row["kinematic_episodes"] >= 6 and row["cost_on_worlds_searched"] >= 1.0
    assert "belief_optimum_on_worlds_searched" not in row and 0 <= row["mujoco_successes"] <= 2
    monkeypatch.setattr("sys.argv", [*argv, "--search-worlds", "0"])
    with pytest.raises(SystemExit) as exc:
        mod.main()
    assert exc.value.code == 2 and "--search-worlds must be at least 1" in capsys.readouterr().err


@pytest.mark.parametrize("exported", [False, True])
def test_pouct_peer_smoke(capsys, monkeypatch, exported):
    pytest.importorskip("pomdp_py", reason="needs the extra crmgrasp[pomdp]")
    mod = _bench("pouct_peer")
    argv = ["pouct_peer.py", "--task", "paper-box", "--sims", "10", "--episodes", "3"]
    monkeypatch.setattr("sys.argv", argv + ["--exported"] * exported)
    mod.main()
    (row,) = json.loads(capsys.readouterr().out)["rows"]
    assert row["episodes"] == 3 and row["belief_policy_same_worlds"] >= 1.0
    assert row["planner"] == ("POUCT on the exported POMDP" if exported else "POUCT on the simulator")
    assert ("pbvi_same_worlds" in row) == exported and ("belief_refills" in row) != exported


@pytest.mark.parametrize("learner", ["pooled-vi", "backoff-vi"])
def test_error_cost_learning_smoke(capsys, monkeypatch, learner):
    spec = importlib.util.spec_from_file_location("error_cost_learning", BENCH.parent / "error_cost_learning.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    argv = ["error_cost_learning.py", "--task", "notch-or-box", "--episodes", "200", "--seeds", "1"]
    setting = ["--param", "plan_every=50"] if learner == "backoff-vi" else []  # an integer parameter
    monkeypatch.setattr("sys.argv", [*argv, "--worlds", "20", "--test", "30", "--learner", learner, *setting])
    mod.main()
    (row,) = json.loads(capsys.readouterr().out)["rows"]
    assert row["params"] == ({"plan_every": 50} if setting else {})
    assert row["cost"] == 30.0 and row["optimum"]["mean_cost"] >= 1.0 and len(row["per_seed"]) == 1
    assert row["learner"] == learner and row["per_seed"][0]["success"] >= 0.9  # evaluated on its own histories
    assert row["k"] == mod.ORDERS[learner]


def test_step_breakdown_smoke(capsys):
    """The breakdown times consecutive batches of a running vector env on both backends."""
    spec = importlib.util.spec_from_file_location("step_breakdown", BENCH.parent / "step_breakdown.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    res = mod.main()
    assert res["numba"]["vector_step_batch_1024_us"] > 0 and res["reference"]["vector_step_batch_128_us"] > 0
    assert res["corner_acceptance_uniform_proposal"] < res["corner_acceptance_tight_proposal"]
    assert json.loads(capsys.readouterr().out) == res


def test_bench_tripod_smoke():
    spec = importlib.util.spec_from_file_location("bench_tripod", BENCH.parent / "bench_tripod.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    res = mod.main(steps=5, rounds=1)
    assert res["box3d3f_us"] > 0 and res["cup3d3f_reference_us"] > 0 and res["cartpole_us"] > 0
    assert res["box3d3f_lf_only_us"] > 0 and res["cup3d3f_lf_only_over_compiled"] > 0
    assert res["box3d3f_decided_step_alone_us"] > 0 and res["cup3d3f_decided_over_cartpole"] > 0
    assert 0 < res["box3d3f_least_friction_us"] < res["box3d3f_least_friction_readable_us"]
    assert res["cup3d3f_least_friction_us"] > 0 and res["cup3d3f_least_friction_search_us"] > 0
    assert res["box3d3f_programs_per_configuration"] < res["box3d3f_programs_per_configuration_search"]
    assert res["box3d3f_programs_per_configuration_search"] < res["box3d3f_programs_per_configuration_bisection"]
    assert res["box3d3f_crossing_mu_goal_against_search"] == 0 and res["cup3d3f_least_friction_decided_search_us"] > 0
    assert 0 < res["box3d3f_step_alone_us"] <= res["box3d3f_us"] and res["cartpole_step_alone_us"] > 0


def test_bench_references_smoke(monkeypatch, capsys):
    spec = importlib.util.spec_from_file_location("bench_references", BENCH.parent / "bench_references.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    monkeypatch.setattr(mod, "CASES", (("paper-box", None, 60), ("u-handle", 5, 40)))
    res = mod.main(quick=True, run=mod.one)  # in this process (the script runs each in a fresh one)
    calls = []
    again = mod.main(quick=True, run=lambda *a: calls.append(a[4:]) or mod.one(*a[:4]), before="/elsewhere")
    assert calls.count(("/elsewhere",)) == 2 and again["paper-box"]["before_over_auto"] > 0
    assert set(res) == {"paper-box", "u-handle-grid5"}
    for row in res.values():
        assert row["starts"] == 6 if row is res["paper-box"] else row["starts"] == 4
        assert row["belief_optimum"] >= row["clairvoyant_bound"] > 0 and row["seconds_reference"] > 0
        assert row["reference_over_auto"] > 0


def test_family_learning_pool_and_reference_bias_smoke():
    spec = importlib.util.spec_from_file_location("family_learning", BENCH.parent / "family_learning.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    from crmgrasp.experiments._episodes import episode_records
    from crmgrasp.planners.references import BeliefPolicy, belief_optimum, sample_starts, ungraspable_fraction
    from crmgrasp.tasks import make_task

    task = make_task("u-handle")
    small = mod.task_row("u-handle", ("pooled-vi",), 10, range(1), 12)
    pooled = mod.task_row("u-handle", ("pooled-vi",), 10, range(1), 12, pool=36)
    same = mod.task_row("u-handle", ("pooled-vi",), 10, range(1), 12, pool=12)
    assert (same["optimum"], same["pooled-vi"]["gap"]) == (small["optimum"], small["pooled-vi"]["gap"])
    assert (small["pool"], pooled["pool"]) == (12, 36) and small["graspable"] == pooled["graspable"]
    planned = sample_starts(task, 36, 10_000)
    planner = BeliefPolicy(task, planned)
    costs = [len(r.actions) for r in episode_records(task, lambda: planner, planned[:12], 0)]
    assert pooled["optimum"] == round(sum(costs) / 12, 4)  # the 36-world policy, scored on the first 12
    judged = mod.task_row("u-handle", ("pooled-vi",), 10, range(1), 12, n_planner=24)
    other = BeliefPolicy(task, sample_starts(task, 24, 30_000), fallback="nearest")
    costs = np.array([len(r.actions) for r in episode_records(task, lambda: other, planned[:12], 0)])
    grasp = np.array([ungraspable_fraction(task, [w]) == 0.0 for w in planned[:12]])
    assert judged["planner"]["mean"] == round(float(costs.mean()), 4) and judged["planner"]["planned_worlds"] == 24
    assert judged["planner"]["mean_graspable"] == round(float(costs[grasp].mean()), 4)
    learner = (1 + judged["pooled-vi"]["gap_graspable"][0]) * judged["optimum_graspable"]  # its graspable mean
    expected = learner / judged["planner"]["mean_graspable"] - 1  # within the rounding of the printed gap
    assert abs(judged["pooled-vi"]["gap_to_planner_graspable"][0] - expected) < 1e-3
    restarted = mod.task_row("u-handle", ("pooled-vi",), 10, range(1), 12, n_planner=24, fallback="restart")
    other = BeliefPolicy(task, sample_starts(task, 24, 30_000))  # the default fallback: restart
    costs = np.array([len(r.actions) for r in episode_records(task, lambda: other, planned[:12], 0)])
    assert restarted["planner"]["mean"] == round(float(costs.mean()), 4)
    assert restarted["planner"]["fallback"] == "restart" and judged["planner"]["fallback"] == "nearest"
    spec = importlib.util.spec_from_file_location("reference_bias", BENCH.parent / "reference_bias.py")
    bias = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bias)
    res = bias.main(["u-handle"], [6, 12], 12, 10)["u-handle"]
    worlds = sample_starts(task, 12, 10_000)
    assert res["12"]["lower"] == round(belief_optimum(task, worlds), 4)  # in-sample per world = the optimum
    blocks = (belief_optimum(task, worlds[:6]) + belief_optimum(task, worlds[6:])) / 2
    assert res["6"]["lower"] == round(blocks, 4) and res["6"]["blocks"] == 2
    assert res["clairvoyant_heldout"] <= res["6"]["upper"] and res["12"]["upper"] <= task.max_steps
    with pytest.raises(SystemExit, match="divide the pool"):
        bias.main(["u-handle"], [5], 12, 10)
    gridded = bias.main(["u-handle"], [6], 6, 4, grid=3)
    assert gridded["offset_grid"] == 3
    grid = offset_grid(task, 3)
    assert gridded["u-handle"]["6"]["lower"] == round(belief_optimum(grid, sample_starts(grid, 6, 10_000)), 4)
    with pytest.raises(CrmgraspError, match="other CRMs than task 'u-handle-grid3'"):
        belief_optimum(grid, worlds[:6])
    near = bias.main(["u-handle"], [6, 12], 12, 10, fallback="nearest")
    assert near["fallback"] == "nearest" and near["u-handle"]["12"]["lower"] == res["12"]["lower"]
    assert res["clairvoyant_heldout"] <= near["u-handle"]["6"]["upper"] <= task.max_steps


def test_handover_ends_are_the_two_policies():
    """Handing over after 0 CRMs is the other policy alone, after the step limit the first alone;
    the learner alone scores as `family_learning.py` scores the same seed's greedy policy."""
    spec = importlib.util.spec_from_file_location("handover", BENCH.parent / "handover.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    row = mod.task_rows("u-handle", "backoff-vi", 2, 40, range(3, 4), 16, 0, (0, 1, 10))
    alone = row["learner alone"]
    assert row["learner then optimum, 0"]["gap_graspable"] == [0.0] and row["learner then optimum, 0"]["lost"] == [0]
    assert row["optimum then learner, 0"] == alone and row["learner then optimum, 10"] == alone
    assert row["optimum then learner, 10"]["gap_graspable"] == [0.0]
    spec = importlib.util.spec_from_file_location("family_learning", BENCH.parent / "family_learning.py")
    fam = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(fam)
    same = fam.task_row("u-handle", ("backoff-vi",), 40, range(3, 4), 16, k=2)["backoff-vi"]
    assert alone["gap_graspable"] == same["gap_graspable"] and alone["lost"] == same["fails_graspable"]
    assert alone["gap_graspable"][0] > 0.0  # 40 episodes are not enough: the two ends differ


def test_memory_projection_full_history_is_the_optimum():
    """The whole history's table is the optimum on the worlds it was made from (the optimum is
    a function of it); the k-order memories of the learners agree with it less or as much, and
    a k = 1 table backs off to the current observation's, as documented; the learner runs and is
    taught by the optimum, whose CRMs it then follows unless epsilon draws others."""
    spec = importlib.util.spec_from_file_location("memory_projection", BENCH.parent / "memory_projection.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    from crmgrasp.planners.references import belief_optimum, sample_starts
    from crmgrasp.tasks import make_task

    res = mod.main("u-handle", 40, 20)
    task = make_task("u-handle")
    assert res["optimum"] == round(belief_optimum(task, sample_starts(task, 40, 10_000)), 4)
    assert res["full"]["agree"] == 1.0 and res["full"]["cost_on_worlds"] == res["optimum"]
    assert res["k0"]["agree"] <= res["k1"]["agree"] <= res["k2"]["agree"] <= res["k3"]["agree"] <= 1.0
    assert res["k0"]["values"] <= res["k1"]["values"] <= res["k2"]["values"] <= res["full"]["values"]
    for half in ("k1+previous_crm", "k1+previous_obs"):  # each a function of k2, k1 a function of each
        assert res["k1"]["values"] <= res[half]["values"] <= res["k2"]["values"]
        assert res["k1"]["agree"] <= res[half]["agree"] <= res["k2"]["agree"]
    for name in mod.FEATURES:
        assert res["optimum"] <= res[name]["cost_on_worlds"] <= task.max_steps
        assert 0.0 <= res[name]["success_on_fresh"] <= 1.0
    res = mod.main("u-handle", 12, 10, learn=(30,), seeds=2)  # the families preset on the same worlds
    got = res["families_preset_30"]
    for where in ("worlds", "fresh"):
        assert len(got[f"cost_on_{where}"]) == len(got[f"success_on_{where}"]) == 2
        assert all(1.0 <= c <= task.max_steps for c in got[f"cost_on_{where}"])
    again = mod.learned(task, 30, 1, sample_starts(task, 12, 10_000), sample_starts(task, 10, 20_000))
    assert again["cost_on_fresh"] == got["cost_on_fresh"][:1]  # seed 0 alone: the same policy
    res = mod.main("u-handle", 12, 10, seeds=2, teach=(30,), epsilon=0.2)  # taught by the optimum
    got = res["taught_30"]
    assert got["epsilon"] == 0.2 and len(got["cost_on_fresh"]) == 2
    assert all(1.0 <= c <= task.max_steps for c in got["cost_on_worlds"] + got["cost_on_fresh"])
    worlds, fresh = sample_starts(task, 12, 10_000), sample_starts(task, 10, 20_000)
    assert mod.taught(task, 30, 1, 0.2, worlds, fresh)["cost_on_fresh"] == got["cost_on_fresh"][:1]
    from crmgrasp.planners.references import BeliefPolicy
    from crmgrasp.sim import run_episode

    _, make = mod.families_learner(task)

    def actions(policy: object, w: object) -> tuple:
        ep = run_episode(task, policy, np.random.default_rng(0), start=w, trace=True)
        return tuple(int(t.action) for t in ep.trace)

    alone = [actions(BeliefPolicy(task, worlds), w) for w in worlds]
    for eps, same in ((0.0, True), (1.0, False)):  # without draws the taught CRMs are the optimum's
        teacher = mod.Taught(*make(), BeliefPolicy(task, worlds), eps, np.random.default_rng(1))
        assert ([actions(teacher, w) for w in worlds] == alone) is same
    m = mod.Memory(5)
    m.push(2, 7, True)
    m.push(3, 9, False)
    assert (m.last(0), m.last(1), m.last(2), m.last(3)) == ((9,), (9, 3), (9, 3, 7, 2), (9, 3, 7, 2, 5))
    assert mod.FEATURES["k1+errored"](m) == ((9, 3), frozenset({2}))
    assert mod.FEATURES["k1+previous_crm"](m) == ((9, 3), (2,)) and mod.FEATURES["k1+previous_obs"](m) == ((9, 3), (7,))


def test_bench_commits_times_a_command_on_two_trees_and_compares_their_files(capsys):
    import shutil
    import subprocess

    root = BENCH.parents[1]
    inside = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, check=False)
    if shutil.which("git") is None or inside.returncode != 0:
        pytest.skip("bench_commits needs git and a checkout with a commit")
    spec = importlib.util.spec_from_file_location("bench_commits", BENCH.parent / "bench_commits.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    command = ["learn", "--task", "paper-box", "--agent", "sarsa", "--trials", "1", "--episodes", "5"]
    try:
        res = mod.main("HEAD", [*command, "--backend", "reference", "--eval-episodes", "10"], rounds=1, warm_up=False)
    except SystemExit as e:  # a checkout git will not add a worktree to (read-only, another owner)
        if "cannot check out" in str(e):
            pytest.skip(str(e))
        raise
    assert res["ref_s"] > 0 and res["tree_s"] > 0 and res["tree_over_ref"] > 0
    assert res["files"] >= 3 and res["files_differ"] == []  # the learned policy is the same on both trees
    assert "| files the same |" in capsys.readouterr().out
    with pytest.raises(SystemExit, match="cannot check out 'no-such-ref'"):
        mod.main("no-such-ref", command, rounds=1, warm_up=False)
    with pytest.raises(SystemExit, match=r"the command failed .*unknown task"):
        mod.main("HEAD", ["learn", "--task", "no-such-task"], rounds=1, warm_up=False)
    listed = subprocess.run(["git", "-C", str(root), "worktree", "list"], capture_output=True, text=True, check=True)
    assert "bench-commits-" not in listed.stdout  # every temporary worktree removed


def test_compare_runs_drops_timings_and_finds_a_changed_result(tmp_path, capsys):
    """``compare_runs.py``, which the notes' "the same files" claims rest on: two runs that differ
    only in wall-clock fields and provenance are the same; a changed number, a missing file, a
    path that is not a folder and two folders without results are not."""
    spec = importlib.util.spec_from_file_location("compare_runs", BENCH.parent / "compare_runs.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    a, b = tmp_path / "a", tmp_path / "b"
    for root, secs, host in ((a, "1.5", "x"), (b, "9.25", "y")):
        (root / "fig").mkdir(parents=True)
        (root / "fig" / "data.csv").write_text(f"episode,crms,seconds\n1,1.66,{secs}\n")
        (root / "run.json").write_text(
            json.dumps({"status": "completed", "host": host, "summary": {"crms": 1.66, "seconds": float(secs)}})
        )
        (root / "README.md").write_text(
            f"| quantity | ours | seconds |\n| --- | --- | --- |\n| crms | 1.66 | {secs} |\nran in {secs} s\n"
        )
    assert mod.main([str(a), str(b)]) == 0
    assert "3 of 3 files the same" in capsys.readouterr().out
    (b / "fig" / "data.csv").write_text("episode,crms,seconds\n1,1.67,9.25\n")
    assert mod.main([str(a), str(b)]) == 1
    assert "fig/data.csv: differs" in capsys.readouterr().out
    (b / "fig" / "data.csv").unlink()
    assert mod.main([str(a), str(b)]) == 1
    assert "fig/data.csv: only in A" in capsys.readouterr().out
    assert mod.main([str(a), str(tmp_path / "nope")]) == 2
    assert "is not a folder" in capsys.readouterr().out
    (tmp_path / "e1").mkdir()
    (tmp_path / "e2").mkdir()
    assert mod.main([str(tmp_path / "e1"), str(tmp_path / "e2")]) == 2


def _bench(name: str):  # type: ignore[no-untyped-def]
    """The benchmark script ``benchmarks/<name>.py`` as a module."""
    spec = importlib.util.spec_from_file_location(name, BENCH.parent / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_metric_noise_smoke(capsys):
    res = _bench("metric_noise").main(train_episodes=20, lengths=(12, 15), seeds=2)
    assert 1.0 <= res["fixed_policy_greedy_mean_steps"] <= 10.0
    assert set(res) >= {"episodes_to_5pct_over_12", "mean_over_15", "episodes_to_5pct_over_12_seeds_0_1"}
    assert len(res["episodes_to_5pct_over_12_seeds_0_1"]) == 2


def test_deep_seeds_smoke():
    from crmgrasp.agents.deep import deep_available

    if not deep_available():
        pytest.skip("needs the extra: pip install 'crmgrasp[deep]'")
    res = _bench("deep_seeds").main(seeds=1, total_steps=128, starts=20)
    row = res["seeds"][0]
    assert res["total_steps"] == 128 and res["starts"] == 20
    assert 1.0 <= row["mean_crms"] <= 10.0 and row["ci95"][0] <= row["mean_crms"] <= row["ci95"][1]


def test_greedy_variants_smoke(capsys):
    """Every variant scores; the recording stepper leaves training as it is (the same counts)."""
    from crmgrasp.agents.training import train_trials
    from crmgrasp.tasks import make_task

    spec = importlib.util.spec_from_file_location("greedy_variants", BENCH.parent / "greedy_variants.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    out = mod.main(["--episodes", "40", "--seeds", "1", "--worlds", "20", "--pool", "20"])
    assert json.loads(capsys.readouterr().out)["pool"] == 20
    (value,) = out["trie_tree_value"]
    assert value[1] >= value[0] and value[2] >= 0  # the search keeps only changes that raise the tree's value
    for v in mod.VARIANTS:
        (gap,) = out[v]["gap_graspable"]
        assert gap >= -1.0 and len(out[v]["fails_graspable"]) == 1
    task, made = make_task("u-handle"), []
    params = {"symmetric": True, **mod.PRESET}
    kw = {"trials": 1, "episodes": 40, "seed": 3, "k": 2, "eval_episodes": 0, "params": params}
    plain = train_trials(task, "backoff-vi", **kw).agents[0]
    recorded = train_trials(task, "backoff-vi", **kw, stepper=lambda t: made.append(mod.Recording(t)) or made[-1])
    assert recorded.agents[0].inner.counts == plain.inner.counts and len(made[0].episodes) == 40


def test_kernel_fuzz_finds_the_paths_equal_and_names_the_kernels():
    mod = _bench("kernel_fuzz")
    rows = mod.main(["--task", "paper-box", "--task", "triangles-3f", "--worlds", "4", "--steps", "5"])
    rows += mod.main(["--task", "box-3d", "--worlds", "3", "--steps", "4", "--continuous"])
    assert [(r["task"], r["noisy"]) for r in rows[:2]] == [("paper-box", False), ("paper-box", True)]
    assert rows[0]["kernels"] == ["FusedPolygonKernel"] and rows[1]["kernels"] == ["PolygonKernel"]
    assert rows[2]["kernels"] == ["FusedFingersKernel"] and rows[4]["continuous"]
    assert all(r["mismatches"] == 0 and r["steps"] == r["worlds"] * (5 if r["task"] != "box-3d" else 4) for r in rows)


def test_kernel_fuzz_reports_a_kernel_that_differs(monkeypatch):
    """A kernel whose step is off in one field is caught, with the step that differs."""

    from crmgrasp.kernels import kernel_for

    mod = _bench("kernel_fuzz")

    def broken(task, backend):  # type: ignore[no-untyped-def]
        k = kernel_for(task, backend)
        real = k.step_one
        monkeypatch.setattr(k, "step_one", lambda *a: real(*a)._replace(reward=-2.0))
        return k

    monkeypatch.setattr(mod, "kernel_for", broken)
    row = mod.fuzz("paper-box", False, worlds=3, steps=4, seed=0, continuous=False)
    assert row["mismatches"] == 3 and row["steps"] == 3 and "world 0, action" in row["first_mismatches"][0]


def test_task_file_fuzz_passes_the_far_cup_and_reports_what_is_not_one_line(monkeypatch):
    """The cup family posed 1e9 m out (NaN normals before every object was bounded) now fails in
    one line; an exception that is not a CrmgraspError, a warning and a long message are each
    reported with the leaf and value."""
    mod = _bench("task_file_fuzz")
    assert list(mod.leaves({"a": [1, {"b": 2}]})) == [("a",), ("a", 0), ("a", 1), ("a", 1, "b")]
    doc = mod.task_to_dict(mod.make_task("cup-3d"))
    far = mod.mutated(doc, ("family", "pose", "offset", 1), 1e9)
    assert doc["family"]["pose"]["offset"][1] == 0.02 and far["family"]["pose"]["offset"][1] == 1e9
    rng = np.random.default_rng(0)
    assert mod.run_variant(far, rng) is None and mod.run_variant(doc, rng) is None
    monkeypatch.setattr(mod, "HOSTILE", (float("nan"),))
    monkeypatch.setattr(mod, "leaves", lambda d: iter([("mu_goal",), ("max_steps",)]))
    row = mod.fuzz("paper-box", 0)
    assert row == {"task": "paper-box", "variants": 4, "failed": 0, "failures": []}

    def warns(d):  # type: ignore[no-untyped-def]
        import warnings

        warnings.warn("invalid value encountered in divide", RuntimeWarning, stacklevel=1)

    for planted, problem in (
        (lambda d: 1 / 0, "ZeroDivisionError: division by zero"),
        (warns, "RuntimeWarning: invalid value encountered in divide"),
        (lambda d: (_ for _ in ()).throw(mod.CrmgraspError("two\nlines")), "CrmgraspError of 9 chars"),
    ):
        monkeypatch.setattr(mod, "task_from_dict", planted)
        row = mod.fuzz("paper-box", 0)
        assert row["failed"] == 4 and row["failures"][0]["leaf"] == "mu_goal", row
        assert row["failures"][0]["value"] == "nan" and row["failures"][1]["value"] == "delete"
        assert row["failures"][0]["problem"].startswith(problem), row


def test_cli_fuzz_passes_what_it_found_and_reports_what_is_not_one_line(monkeypatch):
    """The command lines the fuzz found (a cell of 1e-320 m: an OverflowError; a 5,000-digit
    choice echoed whole) pass now; a handler that raises, one that writes two lines, one that
    exits 1 and one that outlives the time limit are each told apart."""
    import time

    from crmgrasp._validation import CrmgraspError

    mod = _bench("cli_fuzz")
    cli = importlib.import_module("crmgrasp.cli.main")
    monkeypatch.setattr(mod, "HOSTILE", ("1e-320", "9" * 5000))
    monkeypatch.setattr(mod, "options", lambda command: [("--cell", "cell"), ("--start-preset", "start_preset")])
    out = mod.fuzz(["pomdp"], 30.0)
    assert (out["cases"], out["failed"], out["ran"], out["refused"]) == (4, 0, 0, 4), out
    assert mod.command_line("status", None, "run", "X", {"run": "R"}) == ["status", "X"]

    def boom(args):  # type: ignore[no-untyped-def]
        raise ZeroDivisionError("deep inside")

    def two_lines(args):  # type: ignore[no-untyped-def]
        raise CrmgraspError("two\nlines")

    def slow(args):  # type: ignore[no-untyped-def]
        time.sleep(10)
        return 0

    for planted, outcome, problem in (
        (boom, "failed", "status 1, 1 lines on stderr: 'crmgrasp pomdp: internal error (ZeroDivisionError"),
        (two_lines, "failed", "status 2, 2 lines on stderr"),
        (slow, "time limit", None),
        (lambda args: 0, "ran", None),
    ):
        monkeypatch.setattr(cli, "_cmd_pomdp", planted)
        got, found = mod.run_case(["pomdp", "--out", "x.pomdp"], 0.5)
        assert got == outcome and ((found is None) if problem is None else found.startswith(problem)), found


def test_policy_file_fuzz_passes_a_long_crm_set_and_reports_what_is_not_one_line(monkeypatch, tmp_path):
    """A refine-vi policy's 36 CRMs with one changed: its message echoed both whole sets (900
    characters) before it named the first CRM that differs; a variant that runs passes, and one
    that ends in status 1 or two lines is reported."""
    import sys

    import crmgrasp.cli

    mod = _bench("policy_file_fuzz")
    tree = {"a": list(range(10)), "b": {"c": 1}}
    assert list(mod.leaves(tree)) == [("a",), ("a", 0), ("a", 1), ("a", 2), ("b",), ("b", "c")]
    doc = mod.make_policy("refine-vi", tmp_path)
    assert len(doc["actions"]) == 36 and mod.run_variant(doc, tmp_path / "p.json") is None
    variants = {(leaf, shown): v for leaf, shown, v in mod.variants(doc) if leaf == "actions.0"}
    assert mod.run_variant(variants[("actions.0", "-1")], tmp_path / "p.json") is None  # one short line

    def two_lines(argv):  # type: ignore[no-untyped-def]
        print("a\nb", file=sys.stderr)
        return 2

    for planted, problem in ((lambda argv: 1, "status 1"), (two_lines, "status 2, 2 lines")):
        monkeypatch.setattr(crmgrasp.cli, "main", planted)
        assert mod.run_variant(doc, tmp_path / "p.json").startswith(problem)


def test_env_fuzz_passes_hostile_batches_and_reports_what_is_not_one_line(monkeypatch):
    """Hostile batches on paper-box's vector environments are refused in one line; an exception
    that is not a CrmgraspError, a warning and a long message are each reported."""
    import warnings

    from crmgrasp._validation import CrmgraspError

    mod = _bench("env_fuzz")
    monkeypatch.setattr(mod, "VECTOR_TASKS", ("paper-box",))
    assert mod.fuzz_vectors() == (2 * len(mod.BATCHES), [])

    def warns():  # type: ignore[no-untyped-def]
        warnings.warn("invalid value encountered in divide", RuntimeWarning, stacklevel=1)

    def long():  # type: ignore[no-untyped-def]
        raise CrmgraspError("x" * 400)

    assert mod.attempt(lambda: 1 / 0) == "ZeroDivisionError: division by zero"
    assert mod.attempt(warns) == "RuntimeWarning: invalid value encountered in divide"
    assert mod.attempt(long).startswith("CrmgraspError of 400 chars")
    assert mod.attempt(lambda: None) is None


def test_mushroom_peer_needs_its_own_venv_and_says_so_in_one_line():
    if importlib.util.find_spec("mushroom_rl") is not None:
        pytest.skip("MushroomRL is installed here (its own venv): the message is for the other venvs")
    with pytest.raises(SystemExit, match=r"^MushroomRL is not installed here: run `python benchmarks/mushroom_peer"):
        _bench("mushroom_peer").main(["--seeds", "1", "--episodes", "5"])


def test_mushroom_peer_scores_a_q_table_greedily_with_the_evaluations_ties():
    mod = _bench("mushroom_peer")
    table = np.array([[0.0, -1.0, 0.0], [-2.0, -0.5, -3.0]])
    greedy = mod.GreedyTable(table)
    picks = {greedy.greedy(0, np.random.default_rng(s)) for s in range(20)}
    assert picks == {0, 2} and greedy.greedy(1, np.random.default_rng(0)) == 1 and greedy.n_actions == 3


def test_mushroom_peer_smoke():
    pytest.importorskip(
        "mushroom_rl", reason="MushroomRL runs in .venv-mushroom (benchmarks/mushroom_peer.py --make-venv)"
    )
    res = _bench("mushroom_peer").main(["--seeds", "2", "--episodes", "10", "--task", "paper-box"])
    rows = res["paper-box"]
    assert set(rows) == {"MushroomRL sarsa", "MushroomRL q"}
    assert all(len(r["to_5pct"]) == 2 and set(r["mean_at"]) == {5, 10} for r in rows.values())


def test_mujoco_mesh_seams_smoke():
    """Open cups as their convex pieces against one hull: both bodies measured on the same worlds,
    and ``--extra`` applies to that run only."""
    pytest.importorskip("mujoco", reason="needs the extra crmgrasp[mujoco]")
    import crmgrasp.hardware.mujoco.spatial as stand_in

    mod, before = _bench("mujoco_mesh_seams"), stand_in._geom
    res = mod.main(worlds=2, extra='solref="0.004 1"')
    assert res["worlds"] == 2 and res["worlds_drawn"] >= 2 and 0 <= res["c1_grasps_kinematic"] <= 2
    for body in ("pieces", "one hull"):
        median, p90, most = res[body]["sensed_normal_error_deg_median_p90_max"]
        assert 0.0 <= median <= p90 <= most < 90.0 and 0 <= res[body]["c1_grasps"] <= 2
    assert stand_in._geom is before


def test_study_file_fuzz_passes_what_it_found_and_reports_what_is_not_one_line(monkeypatch, tmp_path):
    """The study variants the fuzz found (``eval_episodes = 0``: a report that raised TypeError;
    a ``[[cell]]`` that is not a table: a 410-character message about a key ``'?'``) pass now;
    every hostile value survives the script's TOML; a variant past the time limit, a report that
    raises and a unit that fails in two lines are each reported."""
    import math
    import tomllib

    mod = _bench("study_file_fuzz")
    task_file_fuzz = mod.task_file_fuzz  # the module the script uses
    for value in task_file_fuzz.HOSTILE:
        back = tomllib.loads(f"v = {mod.toml_value(value)}")["v"]
        assert back == value or (isinstance(value, float) and math.isnan(value) and math.isnan(back)), value
    doc = mod.study_document("random")
    assert doc["cell"] == [{"task": "paper-box", "agent": "random", "k": 1}]
    for found in (task_file_fuzz.mutated(doc, ("eval_episodes",), 0), task_file_fuzz.mutated(doc, ("cell", 0), 3)):
        assert mod.run_variant(found, tmp_path) is None
    monkeypatch.setattr(task_file_fuzz, "HOSTILE", (0,))
    monkeypatch.setattr(task_file_fuzz, "leaves", lambda d: iter([("eval_episodes",)]))
    assert mod.fuzz("random", tmp_path) == {"agent": "random", "variants": 2, "failed": 0, "failures": []}

    monkeypatch.setattr(mod, "SECONDS", 0.001)
    assert mod.run_variant(doc, tmp_path) == "TimeLimitError: still running after 0.001 s"
    monkeypatch.setattr(mod, "SECONDS", 20.0)
    sweep = importlib.import_module("crmgrasp.experiments.sweep")
    monkeypatch.setattr(sweep, "report", lambda folder: float(None))
    assert mod.run_variant(doc, tmp_path).startswith("TypeError: float() argument")
    monkeypatch.setattr(sweep._Unit, "__call__", lambda self: {"status": "failed", "error": "two\nlines"})
    problem = mod.run_variant(doc, tmp_path)
    assert problem.startswith("AssertionError: random-k1-") and problem.endswith(r"seed 0: 'two\nlines'"), problem


def test_run_record_fuzz_passes_what_it_found_and_tells_meaningful_status_1_apart(monkeypatch, tmp_path):
    """A damaged unit ``score`` in a complete learn run (an internal error, after a notice that
    the run was complete) is refused in one line now; status 1 passes only where it means
    something (``status``: not complete; a sweep: a cell failed) and only silently."""
    mod = _bench("run_record_fuzz")
    quiet = "status 1, 0 lines on stderr: ''"
    assert mod.passes(["status", "d"], "failed", quiet) and mod.passes(["sweep", "s.toml"], "failed", quiet)
    assert not mod.passes(["sweep", "report", "d"], "failed", quiet)
    assert not mod.passes(["learn", "--out", "d"], "failed", quiet)
    assert not mod.passes(["status", "d"], "failed", "status 1, 1 lines on stderr: 'internal error'")
    assert not mod.passes(["status", "d"], "time limit", None) and mod.passes(["learn"], "refused", None)
    monkeypatch.setattr(mod.task_file_fuzz, "HOSTILE", ("x", None))
    monkeypatch.setattr(
        mod.task_file_fuzz, "leaves", lambda d: iter([("completed", next(iter(d["completed"])), "score")])
    )
    row = mod.fuzz("learn", tmp_path)  # status runs (it reads the status only), resume is refused
    assert row == {"kind": "learn", "commands": 6, "ran": 3, "failed": 0, "failures": []}, row
    monkeypatch.setattr(mod.task_file_fuzz, "leaves", lambda d: iter([("summary", "greedy_ci95_over_trials")]))
    row = mod.fuzz("sweep-unit", tmp_path)  # the study's first unit result: report and resume
    assert row == {"kind": "sweep-unit", "commands": 6, "ran": 0, "failed": 0, "failures": []}, row
    monkeypatch.setattr(mod, "ARRAY_CHANGES", {"negative": mod.ARRAY_CHANGES["negative"]})
    row = mod.fuzz("learn-trials", tmp_path)  # resumed from negative CRM counts before, without a word
    assert row == {"kind": "learn-trials", "commands": 6, "ran": 0, "failed": 0, "failures": []}, row


def test_first_crm_misses_swaps_only_the_start_choices_and_counts_blocks(capsys):
    """Paper-box seed 1 after 20 episodes opposes at once from the far start, where the
    converged preset moves the far contact first: 1.709 CRMs, 1.659 with that choice swapped
    (docs/results.md); the swap changes the start histories only; blocks of ten are counted."""
    mod = _bench("first_crm_misses")
    out = mod.main(["--seeds", "2", "--first", "0"])
    assert json.loads(capsys.readouterr().out)["seeds"] == [0, 1]
    assert out["within_5pct"] == 2 and out["differ"]["seeds"] == 1 and out["blocks_of_ten"]["of"] == 0
    (row,) = out["differ_seeds"]
    assert row["seed"] == 1 and row["crms"] == 1.709 and row["swapped"] == 1.659
    assert row["counts"].startswith("history 79: ") and "CRM 1: error 1, grasp 1" in row["counts"]
    task = mod.make_task("paper-box")
    policy, reference = mod.learn(task, 20, 1), mod.learn(task, 40, 2)
    starts = sorted(mod.met_starts(task, reference))
    both = mod.swapped(policy, reference, starts)
    assert all(both.table[s] == reference.table[s] for s in starts)
    assert all(both.table[s] == a for s, a in policy.table.items() if s not in starts)
    rows = [{"crms": 1.0 + (i % 7 == 0)} for i in range(20)] + [{"crms": 2.0, "swapped": 1.0}]
    assert mod.summary(rows, 1.5)["blocks_of_ten"] == {"with_9_within": 1, "with_5_within": 2, "of": 2}


def test_env_fuzz_episode_loop_passes_and_catches_a_wrapped_index(monkeypatch):
    """The episode loop refuses every hostile action of paper-box in one line; a step that let a
    negative index through (Python's last CRM) would be reported by the script's own oracle."""
    from crmgrasp.tasks.core import Task

    mod = _bench("env_fuzz")
    monkeypatch.setattr(mod, "VECTOR_TASKS", ("paper-box",))
    assert mod.fuzz_episode_loop() == (3 * (len(mod.ACTIONS) + 1), [])
    assert mod._an_index(np.array(2), 4) and mod._an_index(np.int64(3), 4)
    assert not mod._an_index(True, 4) and not mod._an_index(-1, 4) and not mod._an_index(np.array([1]), 4)
    monkeypatch.setattr(Task, "action_index", lambda self, a: a if a == -1 else Task.action_indices(self, [a], 1)[0])
    _, failures = mod.fuzz_episode_loop()
    assert [f["case"] for f in failures if "no index" in f["problem"]] == ["-1", "-1"]


def test_api_fuzz_passes_and_reports_what_escapes(monkeypatch, capsys, tmp_path):
    """Every hostile argument of the public API is refused in one line (or accepted); a check
    taken away is reported with the call and the argument."""
    monkeypatch.chdir(tmp_path)  # examples() saves a policy file where it runs
    mod = _bench("api_fuzz")
    out = mod.main([])
    assert out["failed"] == 0 and out["calls"] == sum(
        len(mod.HOSTILE) * (len(c.args) + len(c.kwargs)) for c in mod.examples()
    )
    import crmgrasp.model.hand as hand

    monkeypatch.setattr(hand, "check_shape", lambda obj, name="object": obj)
    out = mod.main([])
    hand_calls = {"Hand.contact", "Hand.execute", "Hand.execute with noise", "Hand.execute with a reading"}
    assert out["failed"] == 80 and {f["call"] for f in out["failures"]} == hand_calls
    assert all(f["argument"] == "argument 0" for f in out["failures"])


def test_pomdp_file_fuzz_passes_and_reports_what_escapes(monkeypatch):
    """Every edited ``.pomdp`` file reads or fails in one line naming it; with the range checks
    taken away, the indices past the sizes are reported again."""
    mod = _bench("pomdp_file_fuzz")
    out = mod.main([])
    assert out["failed"] == 0 and out["variants"] > 400
    import crmgrasp.planners.pomdp as pomdp

    monkeypatch.setattr(pomdp, "_check_rows", lambda *args: None)
    out = mod.main([])
    assert out["failed"] >= 10
    assert {f["problem"].split(":")[0] for f in out["failures"]} <= {"ValueError", "IndexError", "MemoryError"}
