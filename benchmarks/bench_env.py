"""Speed benchmarks against Gymnasium's CartPole: ``crmgrasp bench`` from a source checkout.

The benchmark ships with the package (:mod:`crmgrasp.experiments.bench`), so ``crmgrasp
bench`` runs on an installed copy too; this script runs the same.

Usage: ``python benchmarks/bench_env.py [--smoke] [--rounds N] [--seed S]``.
"""

from crmgrasp.experiments.bench import main

if __name__ == "__main__":
    main()
