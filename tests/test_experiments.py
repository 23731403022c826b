import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

from crmgrasp import Error, min_friction
from crmgrasp.cli.main import main
from crmgrasp.experiments import (
    Figure4Config,
    Figure7Config,
    Figure8Config,
    Figure9Config,
    figure_4_opposition_quality,
    figure_7_learning_curve,
    figure_8_strategies,
    figure_9_robonaut_trials,
    reproduce,
)
from crmgrasp.experiments.figure4 import long_side_start


def test_figure4_writes_everything_and_is_deterministic(tmp_path):
    s1 = figure_4_opposition_quality(tmp_path / "r1", Figure4Config(seed=3))
    s2 = figure_4_opposition_quality(tmp_path / "r2", Figure4Config(seed=3))
    assert s1 == s2
    assert (tmp_path / "r1" / "data.csv").read_bytes() == (tmp_path / "r2" / "data.csv").read_bytes()
    with open(tmp_path / "r1" / "data.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 30
    mus = [float(r["min_friction"]) for r in rows]
    assert all(math.isfinite(m) for m in mus) and s1["failures"] == 0
    assert 0.0 < np.median(mus) < 0.1  # noise of 3 deg / 2 mm: near-antipodal grasps
    cfg = json.loads((tmp_path / "r1" / "config.json").read_text())
    assert cfg["config"]["sigma_n_deg"] == 3.0 and cfg["summary"]["trials"] == 30
    assert (tmp_path / "r1" / "figure4.png").stat().st_size > 1000


def test_figure4_without_noise_is_exact(tmp_path):
    s = figure_4_opposition_quality(
        tmp_path, Figure4Config(sigma_n_deg=0.0, sigma_p=0.0, palm_tolerance_deg=0.0, trials=10)
    )
    assert s["failures"] == 0 and s["max_min_friction"] == 0.0


def test_long_side_starts(task):
    rng = np.random.default_rng(0)
    for _ in range(50):
        cfg, fingers = long_side_start(task, rng, 0.10)
        assert abs(cfg[fingers].ny) == 1.0  # on a long (horizontal) side
        thumb = "b" if fingers == "a" else "a"
        from crmgrasp import CRM

        out = task.hand.execute(task.obj, cfg, CRM(thumb, fingers, 0.0))
        assert out.error is Error.NONE and min_friction(out.config) == 0.0


def test_figure7_small(tmp_path):
    from crmgrasp.experiments.figure7 import PAPER_LEARNER
    from crmgrasp.experiments.learning import LearnerSpec

    cfg = Figure7Config(
        trials=2,
        episodes=40,
        eval_episodes=20,
        learners=(PAPER_LEARNER, LearnerSpec("random", 2, {}, "random")),
        ablation_ks=(0, 2),
    )
    s = figure_7_learning_curve(tmp_path, cfg)
    for name in (
        "curves.csv",
        "checkpoints.csv",
        "learners.csv",
        "figure7.png",
        "figure7_greedy.png",
        "figure7_k_ablation.png",
        "policy.json",
        "config.json",
    ):
        assert (tmp_path / name).exists(), name
    with open(tmp_path / "curves.csv") as fh:
        rows = list(csv.reader(fh))
    assert len(rows) == 41 and rows[0][:3] == ["episode", "SARSA k=2 (paper) mean", "SARSA k=2 (paper) sem"]
    assert "sarsa_k0_greedy_mean_steps" in s and "best_greedy_episodes_to_5pct" in s
    with open(tmp_path / "checkpoints.csv") as fh:
        ck = list(csv.reader(fh))
    assert [int(r[0]) for r in ck[1:]] == [5, 10, 15, 20, 30, 40]
    with open(tmp_path / "learners.csv") as fh:
        learners = list(csv.DictReader(fh))
    assert {"episodes_to_5pct", "greedy_episodes_to_5pct"} <= set(learners[0])
    assert figure_7_learning_curve(tmp_path / "again", cfg) == s


def test_figures_8_and_9(tmp_path):
    s8 = figure_8_strategies(tmp_path / "f8", Figure8Config(train_trials=2, train_episodes=1500))
    assert len(s8) == 3
    assert (tmp_path / "f8" / "figure8.gif").read_bytes()[:6] == b"GIF89a"
    assert (tmp_path / "f8" / "figure8.png").exists() and (tmp_path / "f8" / "rollouts.csv").exists()
    s9 = figure_9_robonaut_trials(tmp_path / "f9", Figure9Config(train_trials=2, train_episodes=1500))
    assert s9["trials"] == 11 and s9["successes"] >= 10
    before, after = s9["centroid before CRM 1"], s9["centroid after last CRM"]
    assert before[0] > 1.5 and after[0] < 0.2 and after[1] < 0.03  # rho ~2 -> ~0: separate clusters
    assert figure_9_robonaut_trials(tmp_path / "f9b", Figure9Config(train_trials=2, train_episodes=1500)) == s9


@pytest.mark.slow
def test_reproduce_index_and_cli(tmp_path, capsys, monkeypatch):
    """The README's main command as a default install runs it: without the extras, so the
    MuJoCo experiments are skipped and listed so in the index, and the comparison has no deep
    peer (each of those has tests of its own: tests/test_physics_mujoco*.py,
    tests/test_mujoco_learning.py, tests/test_deep.py)."""
    import crmgrasp.experiments.compare
    import crmgrasp.hardware.mujoco
    from crmgrasp._validation import CrmgraspError
    from crmgrasp.experiments.registry import NEEDS_MUJOCO
    from crmgrasp.experiments.reproduce import full_run_rows, record_full_run

    monkeypatch.setattr(crmgrasp.hardware.mujoco, "mujoco_available", lambda: False)
    monkeypatch.setattr(crmgrasp.experiments.compare, "deep_available", lambda: False)
    res = reproduce(tmp_path / "a", ["figure4"], quick=True)
    assert set(res) == {"figure4"}
    index = (tmp_path / "a" / "README.md").read_text()
    assert "figure4/figure4.png" in index and "| figure | quantity | ours | full run | paper |" in index
    assert "Regenerate with `crmgrasp reproduce figure4 --quick --seed 0`." in index  # the experiments asked for
    assert main(["reproduce", "--quick", "--quiet", "--out", str(tmp_path / "b")]) == 0
    out = capsys.readouterr().out
    for name in ("figure4:", "figure7:", "figure8:", "figure9:", "index:"):
        assert name in out
    assert "{'" not in out and "': " not in out  # tables for reading, not raw Python dicts
    index = (tmp_path / "b" / "README.md").read_text()
    assert "figure9/figure9.png" in index and "1.8" in index
    assert "Regenerate with `crmgrasp reproduce --quick --seed 0`." in index  # all of them
    assert "paper SARSA: greedy CRMs per episode | " in index and "(not converged at 5 trials x 300 episodes)" in index
    assert "None" not in index
    for name in NEEDS_MUJOCO:
        assert f"| {name} | skipped: needs `pip install 'crmgrasp[mujoco]'` |" in index
        assert not (tmp_path / "b" / name).exists()
    full = full_run_rows()["figure7 | paper SARSA: greedy CRMs per episode"]
    assert f"| {full} |" in index.split("paper SARSA: greedy CRMs per episode", 1)[1].splitlines()[0]
    with pytest.raises(CrmgraspError, match="not a complete full-budget reproduce run"):
        record_full_run(tmp_path / "b")  # a quick run is no reference
    # a second reproduce into the same folder is refused; --resume reuses every finished experiment
    assert main(["reproduce", "--quick", "--quiet", "--out", str(tmp_path / "b")]) == 2
    before = (tmp_path / "b" / "README.md").read_bytes()
    assert main(["reproduce", "--quick", "--quiet", "--resume", "--out", str(tmp_path / "b")]) == 0
    assert (tmp_path / "b" / "README.md").read_bytes() == before
    assert main(["reproduce", "figure4", "--quick", "--resume", "--out", str(tmp_path / "b")]) == 2
    assert "experiments" in capsys.readouterr().err
    _same_in_worker_processes(tmp_path / "b", tmp_path / "two")
    _same_on_the_reference_kernel(tmp_path / "b", tmp_path / "reference")


def _same_on_the_reference_kernel(one: Path, out: Path) -> None:
    """Figures 8 and 9 (each trains its policy) on the readable reference kernel write the CSV
    and JSON files of the compiled run in ``one`` (the whole quick run above), byte for byte."""
    reproduce(out, ["figure8", "figure9"], quick=True, backend="reference")
    files = sorted(p.relative_to(one) for p in (one / "figure8").rglob("*") if p.suffix in (".csv", ".json"))
    files += sorted(p.relative_to(one) for p in (one / "figure9").rglob("*") if p.suffix in (".csv", ".json"))
    assert len(files) >= 4
    for f in files:
        assert (out / f).read_bytes() == (one / f).read_bytes(), f


def _same_in_worker_processes(one: Path, out: Path) -> None:
    """Figures 4, 8 and 9 (each draws starts; 8 and 9 train a policy) run in two worker
    processes give the summaries and files of the one-process run in ``one`` (the whole quick
    run above). Figure 7, the longest, is left out for time."""
    names = ["figure4", "figure8", "figure9"]
    two = reproduce(out, names, quick=True, jobs=2)
    done = json.loads((one / "run.json").read_text())["completed"]
    strip = lambda s: {k: v for k, v in s.items() if k != "seconds"}  # noqa: E731
    mine = json.loads(json.dumps({k: strip(v) for k, v in two.items()}))  # as run.json holds them
    assert {k: strip(done[k]["summary"]) for k in names} == mine
    files = sorted(f for name in names for f in (one / name).rglob("*.csv"))
    assert len(files) == 3
    for f in files:
        assert f.read_bytes() == (out / f.relative_to(one)).read_bytes(), f
