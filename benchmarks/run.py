"""Speed benchmarks against Gymnasium (see ``bench_env.py`` beside this file).

Usage: ``python benchmarks/run.py [--smoke] [--rounds N]``; the same as ``crmgrasp bench``.
"""

from bench_env import main

if __name__ == "__main__":
    main()
