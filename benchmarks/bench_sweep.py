"""Sweep throughput: local worker processes against one, and Ray's overhead.

Prints one JSON object:

* ``local_speedup``: a 40-cell study (SARSA, 10 trials x 500 episodes per cell, alpha x q0 x
  seeds) with ``--jobs 2`` against ``--jobs 1``, same process, same results (target >= 1.7 on
  2 cores);
* with Ray installed: ``ray_startup_seconds`` (a local instance, first task to result),
  ``ray_1000_tiny_cells_seconds`` and the larger of the peak RSS of this process and of its
  largest child process (``ray_peak_rss_mb``) for 1,000 cells of 1 trial x 1 episode.

Usage: ``python benchmarks/bench_sweep.py``.
"""

from __future__ import annotations

import json
import resource
import tempfile
import time
from pathlib import Path

from crmgrasp.experiments.runs import RunFolder
from crmgrasp.experiments.study import study_from_dict
from crmgrasp.experiments.sweep import run_study


def _run(doc: dict, jobs: int, executor: str = "local") -> tuple[float, bytes]:
    study = study_from_dict(doc)
    with tempfile.TemporaryDirectory() as tmp:
        with RunFolder(Path(tmp) / "run", "sweep", study.name, {"study": study.to_dict()}, argv=[]) as run:
            t0 = time.perf_counter()
            run_study(study, run, jobs=jobs, executor=executor)
            seconds = time.perf_counter() - t0
        return seconds, (run.path / "results.csv").read_bytes()


def main() -> dict:
    out: dict = {}
    doc = {
        "name": "bench",
        "trials": 10,
        "episodes": 500,
        "eval_episodes": 50,
        "seeds": [0, 1, 2, 3, 4],
        "grid": {"agent": ["sarsa"], "alpha": [0.1, 0.3, 0.6, 1.0], "q0": [0.0, -1.0]},
    }
    _run({**doc, "seeds": [0], "episodes": 5}, 1)  # compile the kernels before timing
    one, a = _run(doc, 1)
    two, b = _run(doc, 2)
    out.update(local_one_job_seconds=round(one, 2), local_two_jobs_seconds=round(two, 2))
    out["local_speedup"] = round(one / two, 2)
    out["local_same_results"] = a == b
    try:
        import ray
    except ImportError:
        out["ray"] = "not installed"
        return out
    t0 = time.perf_counter()
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    ray.get(ray.remote(lambda: 1).remote())
    out["ray_startup_seconds"] = round(time.perf_counter() - t0, 2)
    tiny = {
        "name": "tiny",
        "trials": 1,
        "episodes": 1,
        "eval_episodes": 1,
        "seeds": list(range(250)),
        "grid": {"agent": ["sarsa", "q"], "alpha": [0.3, 0.6]},
    }
    seconds, _ = _run(tiny, 2, "ray")
    ray.shutdown()
    out["ray_1000_tiny_cells_seconds"] = round(seconds, 2)
    peak = max(
        resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    )
    out["ray_peak_rss_mb"] = round(peak / 1024, 1)
    return out


if __name__ == "__main__":
    print(json.dumps(main(), indent=2))
