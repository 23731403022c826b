"""Hostile policy files, at scale: saved policies of every kind with each field set to hostile
values, their checksum made to match, then evaluated.

The setup learns (or plans) a short policy of each kind [`KINDS`][] names: the paper's SARSA
(version 2), ``backoff-vi`` with its back-off table (version 3) and with ``skip_errored`` (version
4, ranked tables), ``refine-vi`` on a grid of offsets, the k-order policy search, three fingers
and a spatial task. For each file's document it takes every leaf (a key's value, or an item of
a list; below the top, of a table of more than eight entries, its first three only) and sets it
to each value of ``benchmarks/task_file_fuzz.py``'s ``HOSTILE`` list plus [`MORE`][] (integers
past any index, action lists, 21-digit codes) or deletes it; a table entry's key is also renamed to each of
[`KEYS`][]. The checksum is then recomputed, as a user who edits a file by hand and fixes its
checksum would, so that the variant reaches the loader's checks of every field, and ``crmgrasp
evaluate --policy FILE --episodes 3`` runs it in this process with Python's warnings raised as
errors (``benchmarks/cli_fuzz.py``'s ``run_case``). A variant passes if it exits 0, or exits 2
with one line on standard error of under 400 characters; anything else is reported with the
leaf and value. It prints one JSON object and exits 1 if a variant failed.

The tests of saved policies check each field once; this runs every field of every kind.
Measured 2026-12-07 on the 2-core machine beside other work: 11,396 variants of the 7 kinds in
322 s, none failed. Before that day's fix, 1,453 failed, all one kind: a changed CRM set's
message listed both sets whole (470-910 characters, longer for a finer grid); it now names the
count or the first CRM that differs.

Usage: ``python benchmarks/policy_file_fuzz.py [--kind NAME ...]``.
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import io
import json
import math
import os
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
import cli_fuzz
import task_file_fuzz

MORE: tuple[Any, ...] = (2**40, -(2**40), [[0], [1]], [0, 0], "0", 10**21, [9999])
"""Values beyond the task-file list that a policy's fields invite."""

KEYS: tuple[str, ...] = ("", "x", "-1", "1.5", "1e3", "99999999999999999999999", " 12", "\u0661")
"""Names a table entry's key is renamed to (a state code is a canonical decimal)."""

KINDS: dict[str, list[str]] = {
    "sarsa": ["learn", "--task", "paper-box", "--agent", "sarsa", "--episodes", "40"],
    "backoff-vi": ["learn", "--task", "box-family", "--agent", "backoff-vi", "--k", "2", "--episodes", "60"],
    "skip-errored": ["learn", "--task", "u-handle", "--preset", "families", "--episodes", "60"],
    "refine-vi": ["learn", "--task", "paper-box", "--agent", "refine-vi", "--offset-grid", "9", "--episodes", "40"],
    "plan": ["plan", "--task", "paper-box", "--worlds", "20", "--heldout", "10", "--k", "1"],
    "three-fingers": ["learn", "--task", "triangles-3f", "--agent", "model-vi", "--k", "1", "--episodes", "40"],
    "spatial": ["learn", "--task", "cup-3d", "--agent", "model-vi", "--k", "1", "--episodes", "40"],
}
"""How the setup makes a policy of each kind (``learn`` runs 1 trial and evaluates 5 episodes)."""

DELETE = task_file_fuzz.DELETE
RENAME = object()


def leaves(doc: Any, path: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    """Every leaf's path below ``doc``, depth first, but only the first three entries of a dict
    or list below the top of more than eight (a greedy table has hundreds of the same shape)."""
    items = list(doc.items()) if isinstance(doc, dict) else list(enumerate(doc)) if isinstance(doc, list) else []
    for key, value in items if not path or len(items) <= 8 else items[:3]:
        yield (*path, key)
        yield from leaves(value, (*path, key))


def variants(doc: dict[str, Any]) -> Iterator[tuple[str, str, dict[str, Any]]]:
    """``(leaf, value shown, document)`` of every variant of ``doc`` (module docstring), its
    checksum recomputed."""
    from crmgrasp.agents.policy import policy_digest

    for path in leaves(doc):
        if path == ("sha256",):
            continue
        parent = doc
        for key in path[:-1]:
            parent = parent[key]
        renames = [(RENAME, k) for k in KEYS] if isinstance(parent, dict) and path[0] != "task_spec" else []
        for value, new_key in [*((v, None) for v in (*task_file_fuzz.HOSTILE, *MORE, DELETE)), *renames]:
            if value is RENAME:
                out = copy.deepcopy(doc)
                target = out
                for key in path[:-1]:
                    target = target[key]
                target[new_key] = target.pop(path[-1])
                shown = f"key renamed {new_key!r}"
            else:
                out = task_file_fuzz.mutated(doc, path, value)
                shown = "delete" if value is DELETE else repr(value)
            out["sha256"] = policy_digest(out)
            yield ".".join(map(str, path)), shown, out


def run_variant(doc: dict[str, Any], path: Path) -> str | None:
    """Write ``doc`` to ``path`` and evaluate it (``benchmarks/cli_fuzz.py``'s ``run_case``, 60 s
    at most); ``None`` if that runs or fails in one line, else what went wrong."""
    path.write_text(json.dumps(doc))
    return cli_fuzz.run_case(["evaluate", "--policy", str(path), "--episodes", "3", "--quiet"], 60.0)[1]


def make_policy(kind: str, root: Path) -> dict[str, Any]:
    """The policy document of ``kind``, made by its command line in ``root``."""
    from crmgrasp.cli import main

    argv = [*KINDS[kind], "--out", str(root / kind), "--quiet"]
    if argv[0] == "learn":
        argv += ["--trials", "1", "--eval-episodes", "5"]
    with contextlib.redirect_stdout(io.StringIO()):
        status = main(argv)
    assert status == 0, (kind, status)
    return json.loads((root / kind / "policy.json").read_text())


def fuzz(kinds: list[str]) -> dict[str, Any]:
    """Every variant of each kind's policy: counts and failures."""
    from crmgrasp.kernels import compiling

    rows, t0, after = [], time.perf_counter(), compiling.AFTER
    compiling.AFTER = math.inf  # the notice while numba compiles would be a second line
    try:
        with tempfile.TemporaryDirectory(prefix="crmgrasp-policy-fuzz-") as tmp:
            root = Path(tmp)
            for kind in kinds:
                doc = make_policy(kind, root)
                assert run_variant(doc, root / "same.json") is None, kind  # the file as saved runs
                count, failures = 0, []
                for leaf, shown, variant in variants(doc):
                    count += 1
                    problem = run_variant(variant, root / "variant.json")
                    if problem is not None:
                        failures.append({"leaf": leaf, "value": shown, "problem": problem})
                rows.append({"kind": kind, "variants": count, "failed": len(failures), "failures": failures[:20]})
                print(f"{kind}: {count} variants, {len(failures)} failed", file=sys.stderr, flush=True)
    finally:
        compiling.AFTER = after
    return {
        "variants": sum(r["variants"] for r in rows),
        "failed": sum(r["failed"] for r in rows),
        "seconds": round(time.perf_counter() - t0, 1),
        "kinds": rows,
    }


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kind", action="append", choices=tuple(KINDS), help="(default: every kind)")
    args = parser.parse_args(argv)
    out = fuzz(args.kind or list(KINDS))
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    os.environ.setdefault("MUJOCO_GL", "egl")
    sys.exit(1 if main()["failed"] else 0)
