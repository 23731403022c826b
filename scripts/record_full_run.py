"""Record the index rows of a full ``crmgrasp reproduce`` run as the reference that quick
runs show beside their numbers (``src/crmgrasp/experiments/full_run.json``).

    crmgrasp reproduce --seed 0 --out runs/full      # every extra installed, about 200 s
    python scripts/record_full_run.py runs/full
"""

from __future__ import annotations

import sys

from crmgrasp.experiments.reproduce import record_full_run

if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python scripts/record_full_run.py RUN_DIR  (a complete full-budget reproduce run)")
    print(f"wrote {record_full_run(sys.argv[1])}")
