"""Speed benchmarks against Gymnasium (see :mod:`crmgrasp.bench`).

Usage: ``python benchmarks/run.py [--smoke] [--rounds N]``; the same as ``crmgrasp bench``.
"""

from crmgrasp.bench import main

if __name__ == "__main__":
    main()
