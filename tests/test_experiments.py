import csv
import json
import math

import numpy as np

from crmgrasp import Error, min_friction
from crmgrasp.cli import main
from crmgrasp.experiments import Figure4Config, figure_4_opposition_quality, reproduce
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


def test_reproduce_index_and_cli(tmp_path, capsys):
    res = reproduce(tmp_path / "a", quick=True)
    assert set(res) == {"figure4"}
    index = (tmp_path / "a" / "README.md").read_text()
    assert "figure4/figure4.png" in index
    assert main(["reproduce", "--quick", "--out", str(tmp_path / "b")]) == 0
    out = capsys.readouterr().out
    assert "figure4:" in out and "index:" in out
