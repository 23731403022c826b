"""One ``crmgrasp`` command timed on this tree and on another commit, in the same run, and
their results compared.

A change meant to make something faster must leave its results alone. This runs the same
command with the package's source from a commit (``--ref``, checked out into a temporary git
worktree; the dependencies are this environment's) and from this working tree, alternating,
each run into a fresh folder (``--out DIR --quiet`` appended to the command). Before the timed
rounds each side runs once untimed, so that both have filled their numba caches. It prints the
least wall seconds of each side over ``--rounds`` rounds (the whole process: start-up and
imports included), their ratio (this tree over the commit: below 1, this tree is faster), and
whether the two sides' first timed folders hold the same results, file by file
(``compare_runs.py``: wall-clock fields dropped). Exit status 1 if they differ.

Usage: ``python benchmarks/bench_commits.py [--ref REF] [--rounds 3] [--no-warm-up] --
COMMAND ...``, for example ``python benchmarks/bench_commits.py --ref HEAD~1 -- learn --task
triangles-3f --preset families --trials 1 --episodes 3000``. Prints a table and one JSON object.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent


def _compare_runs():  # type: ignore[no-untyped-def]
    spec = importlib.util.spec_from_file_location("compare_runs", Path(__file__).parent / "compare_runs.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _same(cmp: Any, a: Path, b: Path) -> bool:
    """Whether files ``a`` and ``b`` both exist and hold the same results (``compare_runs``)."""
    return a.exists() and b.exists() and cmp.first_difference(cmp.load(a), cmp.load(b)) is None


def _run(src: Path, command: list[str], out: Path) -> float:
    """Wall seconds of ``python -m crmgrasp COMMAND --out OUT --quiet`` with ``src`` first on
    the path; a failed command stops the benchmark with its last lines."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(src), os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep)}
    t0 = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-m", "crmgrasp", *command, "--out", str(out), "--quiet"],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    seconds = time.perf_counter() - t0
    if done.returncode != 0:
        tail = (done.stderr or done.stdout).strip().splitlines()[-3:]
        raise SystemExit(f"bench_commits: the command failed with {src} first on the path: " + " / ".join(tail))
    return seconds


def main(ref: str, command: list[str], rounds: int = 3, warm_up: bool = True) -> dict[str, object]:
    """Time ``command`` at ``ref`` and on this tree (see the module docstring)."""
    if not command:
        raise SystemExit("bench_commits: give the crmgrasp command after --, e.g. -- learn --task paper-box")
    with tempfile.TemporaryDirectory(prefix="bench-commits-") as tmp:
        tree = Path(tmp) / "ref"
        added = subprocess.run(
            ["git", "-C", str(ROOT), "worktree", "add", "--detach", str(tree), ref],
            capture_output=True,
            text=True,
            check=False,
        )
        if added.returncode != 0:
            raise SystemExit(f"bench_commits: cannot check out {ref!r}: {added.stderr.strip()}")
        try:
            sides = {"ref": tree / "src", "tree": ROOT / "src"}
            if warm_up:
                for name, src in sides.items():
                    _run(src, command, Path(tmp) / f"warm-{name}")
            best = {name: float("inf") for name in sides}
            for i in range(rounds):
                for name, src in sides.items():
                    best[name] = min(best[name], _run(src, command, Path(tmp) / f"{name}-{i}"))
            cmp = _compare_runs()
            a, b = Path(tmp) / "ref-0", Path(tmp) / "tree-0"
            kept = {".csv", ".json", ".md"}
            files = sorted({p.relative_to(r) for r in (a, b) for p in r.rglob("*") if p.suffix in kept})
            differ = [str(f) for f in files if not _same(cmp, a / f, b / f)]
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(tree)], check=False)
    out = {
        "ref": ref,
        "command": " ".join(command),
        "rounds": rounds,
        "ref_s": round(best["ref"], 2),
        "tree_s": round(best["tree"], 2),
        "tree_over_ref": round(best["tree"] / best["ref"], 3),
        "files": len(files),
        "files_differ": differ,
    }
    print("| command | ref s | tree s | tree / ref | files the same |")
    print("| --- | --- | --- | --- | --- |")
    print(
        f"| `{out['command']}` | {out['ref_s']} | {out['tree_s']} | {out['tree_over_ref']} | "
        f"{len(files) - len(differ)} of {len(files)} |"
    )
    return out


if __name__ == "__main__":
    argv = sys.argv[1:]
    split = argv.index("--") if "--" in argv else len(argv)
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--ref", default="HEAD", help="the commit to time against (default HEAD)")
    parser.add_argument("--rounds", type=int, default=3, help="timed rounds, each side once per round (default 3)")
    parser.add_argument("--no-warm-up", action="store_true", help="no untimed first run per side")
    args = parser.parse_args(argv[:split])
    result = main(args.ref, argv[split + 1 :], max(1, args.rounds), not args.no_warm_up)
    print(json.dumps(result))
    sys.exit(1 if result["files_differ"] else 0)
