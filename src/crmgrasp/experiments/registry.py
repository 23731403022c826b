"""The experiments that ``crmgrasp reproduce`` knows: per name, a description, the
runner (``runner(out_dir, seed, quick, context) -> (summary, rows)``) and the images
it writes; each runner's rows put our numbers beside the paper's. The context is
shared by the experiments of one run: ``backend`` (the kernel backend) and what
earlier experiments produced (``policy``: the Figure 7 policy)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

from crmgrasp.experiments.stats import fmt

__all__ = ["EXPERIMENTS", "NEEDS_MUJOCO", "IMAGES", "Row", "Runner"]

Row = tuple[str, object, str]
Runner = Callable[[Path, int, bool, dict[str, Any]], tuple[dict[str, Any], list[Row]]]


def _figure4(out: Path, seed: int, quick: bool, ctx: dict[str, Any]) -> tuple[dict[str, Any], list[Row]]:
    from crmgrasp.experiments.figure4 import Figure4Config, figure_4_opposition_quality

    s: dict[str, Any] = figure_4_opposition_quality(out, Figure4Config(seed=seed))
    return s, [
        ("opposition grasps", f"{s['trials'] - s['failures']} of {s['trials']}", "30 of 30"),
        (
            "median / max min_friction",
            f"{s['median_min_friction']:.3f} / {s['max_min_friction']:.3f}",
            "histogram concentrated below ~0.1",
        ),
    ]


def _figure7(out: Path, seed: int, quick: bool, ctx: dict[str, Any]) -> tuple[dict[str, Any], list[Row]]:
    from crmgrasp.experiments.figure7 import Figure7Config, figure_7_learning_curve

    cfg = Figure7Config(seed=seed)
    if quick:
        cfg = replace(cfg, trials=5, episodes=300, eval_episodes=200, checkpoint_episodes=50)
    s = figure_7_learning_curve(out, cfg, backend=ctx["backend"], progress=ctx.get("progress"), jobs=ctx.get("jobs", 1))
    if not quick:
        ctx["policy"] = str(out / "policy.json")
    return s, [
        ("belief-space optimum, 4,000 starts", s["belief_optimum_4000_starts"], "-"),
        ("clairvoyant bound, 4,000 starts", s["clairvoyant_bound_4000_starts"], "-"),
        ("paper SARSA: greedy CRMs per episode", s["paper_sarsa_greedy_mean_steps"], "1.8 (learning curve)"),
        ("paper SARSA: final training CRMs per episode", s["paper_sarsa_final_mean_steps"], "1.8"),
        (
            "paper SARSA: episodes to within 5% of optimum",
            s["paper_sarsa_episodes_to_5pct"],
            "about 60 (to its own plateau)",
        ),
        ("best learner: episodes to within 5%", f"{fmt(s['best_episodes_to_5pct'])} ({s['best_learner']})", "-"),
        ("paper SARSA: greedy policy within 5% after", s["paper_sarsa_greedy_episodes_to_5pct"], "-"),
        (
            "best learner: greedy policy within 5% after",
            f"{fmt(s['best_greedy_episodes_to_5pct'])} ({s['best_greedy_learner']})",
            "about 60 (SARSA)",
        ),
        ("SARSA k=0 (memoryless) greedy CRMs", s["sarsa_k0_greedy_mean_steps"], "(not run; k = 2 used)"),
    ]


def _figure8(out: Path, seed: int, quick: bool, ctx: dict[str, Any]) -> tuple[dict[str, Any], list[Row]]:
    from crmgrasp.experiments.figure8 import Figure8Config, figure_8_strategies

    s = figure_8_strategies(out, Figure8Config(seed=seed, policy=ctx.get("policy")), backend=ctx["backend"])
    labels = list(s)
    return s, [
        (
            "aliased near-corner starts",
            f"{s[labels[0]]}; mirror: {s[labels[1]]}",
            "oppose one contact; on failure oppose the other",
        ),
        ("long-side contact far from the corner", s[labels[2]], "move it toward the corner (C3/C4), then oppose it"),
    ]


def _figure9(out: Path, seed: int, quick: bool, ctx: dict[str, Any]) -> tuple[dict[str, Any], list[Row]]:
    from crmgrasp.experiments.figure9 import Figure9Config, figure_9_robonaut_trials

    s = figure_9_robonaut_trials(out, Figure9Config(seed=seed, policy=ctx.get("policy")), backend=ctx["backend"])
    return s, [
        ("grasps / trials", f"{s['successes']} / {s['trials']}", "11 / 11"),
        ("CRMs per trial", s["mean_crms"], "2"),
        (
            "cluster centroids (rho, |m|)",
            "; ".join(str(v) for k, v in s.items() if k.startswith("centroid")),
            "(0.7, 1.2); (0.5, 1.2); (~0, ~0) in the paper's units",
        ),
    ]


def _compare(out: Path, seed: int, quick: bool, ctx: dict[str, Any]) -> tuple[dict[str, Any], list[Row]]:
    from crmgrasp.experiments.compare import CompareConfig, compare

    cfg = CompareConfig.quick(seed=seed) if quick else CompareConfig(seed=seed)
    s = compare(out, cfg, backend=ctx["backend"], progress=ctx.get("progress"), jobs=ctx.get("jobs", 1))
    return s, [
        ("best learner, greedy CRMs", f"{fmt(s['best_learner_mean_crms'])} ({s['best_learner']})", "1.8"),
        (
            "belief-space optimum / clairvoyant bound",
            f"{fmt(s['belief_optimum'], 4)} / {fmt(s['clairvoyant_bound'], 4)}",
            "-",
        ),
        ("grasp controller (no learning), CRMs", s["grasp_controller_mean_crms"], "-"),
        ("belief-space policy executed on fresh starts, CRMs", s["belief_policy_executed_mean_crms"], "-"),
    ]


def _sensitivity(out: Path, seed: int, quick: bool, ctx: dict[str, Any]) -> tuple[dict[str, Any], list[Row]]:
    from crmgrasp.experiments.sensitivity import SensitivityConfig, figure_7_sensitivity

    cfg = SensitivityConfig.quick(seed) if quick else replace(SensitivityConfig(), seeds=(seed, seed + 1, seed + 2))
    s = figure_7_sensitivity(out, cfg, backend=ctx["backend"], progress=ctx.get("progress"), jobs=ctx.get("jobs", 1))
    rows: list[Row] = []
    for label, r in s.items():
        rows.append(
            (
                f"{label}: plateau / optimum; episodes to own plateau; to <= 1.89",
                f"{r['plateau']} / {fmt(r['belief_optimum'])}; {r['episodes_to_own_plateau']}; "
                f"{r['episodes_to_paper_level']}",
                "1.8; about 60",
            )
        )
    return s, rows


def _cost_of_failure(out: Path, seed: int, quick: bool, ctx: dict[str, Any]) -> tuple[dict[str, Any], list[Row]]:
    from crmgrasp.experiments.cost_of_failure import CostConfig, cost_of_failure

    cfg = CostConfig.quick(seed) if quick else CostConfig(seed=seed)
    s = cost_of_failure(out, cfg, progress=ctx.get("progress"))
    rows: list[Row] = []
    for name, t in s["tasks"].items():
        for opt, lrn in zip(t["optimal_rows"], t["rows"], strict=True):
            rows.append(
                (
                    f"{name}, error cost {opt['cost']:g}: errors per episode / sense-first / prepare-first "
                    "(optimum; learned)",
                    f"{opt['errors_per_episode']:.3f} / {opt['sense_first_fraction']:.0%} / "
                    f"{opt['other_fraction']:.0%}; {lrn['errors_per_episode']:.3f} / "
                    f"{lrn['sense_first_fraction']:.0%} / {lrn['other_fraction']:.0%}",
                    "costly failures: sense first (Discussion, no experiment)",
                )
            )
    return s, rows


def _generalization(out: Path, seed: int, quick: bool, ctx: dict[str, Any]) -> tuple[dict[str, Any], list[Row]]:
    from crmgrasp.experiments.generalization import GeneralizationConfig, generalization

    cfg = GeneralizationConfig.quick(seed) if quick else GeneralizationConfig(seed=seed)
    s = generalization(out, cfg, progress=ctx.get("progress"))
    rows: list[Row] = []
    for name, f in s["families"].items():
        rows.append(
            (
                f"{name}: held-out / training objects / optimum / out of range, CRMs",
                f"{f['heldout_mean_crms']:.3f} / {f['learner_mean_crms']:.3f} / {f['belief_optimum']:.3f} / "
                f"{fmt(f.get('out_of_range_mean_crms'))}",
                "works throughout the space of object variation (Discussion, no experiment)",
            )
        )
        if "search_heldout_mean_crms" in f:
            rows.append(
                (
                    f"{name}: k = 1 policy search from episodes, held-out CRMs (gap to the optimum)",
                    f"{f['search_heldout_mean_crms']:.3f} ({f['search_gap_to_optimum']:+.1%})",
                    "-",
                )
            )
        if "planner_heldout_mean_crms" in f:
            rows.append(
                (
                    f"{name}: k = 1 policy planned on sampled worlds, held-out CRMs (gap to the optimum)",
                    f"{f['planner_heldout_mean_crms']:.3f} ({f['planner_gap_to_optimum']:+.1%})",
                    "-",
                )
            )
    return s, rows


def _non_convex(out: Path, seed: int, quick: bool, ctx: dict[str, Any]) -> tuple[dict[str, Any], list[Row]]:
    from crmgrasp.experiments.non_convex import NonConvexConfig, non_convex

    s = non_convex(
        out, NonConvexConfig.quick(seed) if quick else NonConvexConfig(seed=seed), progress=ctx.get("progress")
    )
    return s, [
        (
            "U handle: learned / optimum / clairvoyant, CRMs",
            f"{s['learner_mean_crms']:.3f} / {s['belief_optimum']:.3f} / {s['clairvoyant_bound']:.3f}",
            "arbitrary classes of objects, not just convex (Introduction, no experiment)",
        ),
        ("U handle: grasps with a contact inside the handle", f"{s['inside_share']:.0%}", "-"),
    ]


def _spatial(out: Path, seed: int, quick: bool, ctx: dict[str, Any]) -> tuple[dict[str, Any], list[Row]]:
    from crmgrasp.experiments.spatial import SpatialConfig, spatial

    s = spatial(out, SpatialConfig.quick(seed) if quick else SpatialConfig(seed=seed), progress=ctx.get("progress"))
    rows: list[Row] = []
    for name, t in s["tasks"].items():
        learned = " / ".join(f"{v['greedy_mean_crms']:.3f}" for v in t["learners"].values())
        rows.append(
            (
                f"{name}: {' / '.join(t['learners'])} / optimum / clairvoyant, greedy CRMs",
                f"{learned} / {t['belief_optimum']:.3f} / {t['clairvoyant_bound']:.3f}",
                "expected to extend to spatial objects (Discussion, no experiment)",
            )
        )
    return s, rows


def _sensing_row(s: dict[str, Any]) -> Row:
    cs = s["contact_sensing"]
    return (
        f"contact sensing vs MuJoCo contacts ({cs['contacts']} contacts): median position / normal error",
        f"{cs['median_position_error_mm']} mm / {cs['median_normal_error_deg']} deg",
        "(Robonaut load cells; not reported)",
    )


def _figure4_mujoco(out: Path, seed: int, quick: bool, ctx: dict[str, Any]) -> tuple[dict[str, Any], list[Row]]:
    from crmgrasp.experiments.mujoco import MujocoFigure4Config, figure_4_mujoco

    s = figure_4_mujoco(out, MujocoFigure4Config(seed=seed, extra_starts=40 if quick else 100))
    return s, [
        ("MuJoCo opposition grasps", f"{s['trials'] - s['failures']} of {s['trials']}", "30 of 30 (Robonaut)"),
        ("MuJoCo median / max true min_friction", f"{s['median_min_friction']} / {s['max_min_friction']}", "-"),
        _sensing_row(s),
        ("MuJoCo wall time per CRM, median / max", f"{s['median_crm_seconds']} / {s['max_crm_seconds']} s", "-"),
    ]


def _figure9_mujoco(out: Path, seed: int, quick: bool, ctx: dict[str, Any]) -> tuple[dict[str, Any], list[Row]]:
    from crmgrasp.experiments.mujoco import MujocoFigure9Config, figure_9_mujoco

    s = figure_9_mujoco(out, MujocoFigure9Config(seed=seed, policy=ctx.get("policy")), backend=ctx["backend"])
    return s, [
        ("MuJoCo grasps / trials (kinematic policy)", f"{s['successes']} / {s['trials']}", "11 / 11 (Robonaut)"),
        (
            "CRMs per trial: MuJoCo / kinematic, same starts",
            f"{fmt(s['mean_crms_mujoco'])} / {fmt(s['mean_crms_kinematic'])}",
            "2",
        ),
        ("most extra CRMs on MuJoCo in one trial", s["max_extra_crms"], "-"),
        (
            "MuJoCo cluster centroids (rho, |m|)",
            "; ".join(str(v) for k, v in s.items() if k.startswith("centroid")),
            "three clusters",
        ),
    ]


def _spatial_mujoco(out: Path, seed: int, quick: bool, ctx: dict[str, Any]) -> tuple[dict[str, Any], list[Row]]:
    from crmgrasp.experiments.mujoco_spatial import SpatialMujocoConfig, spatial_mujoco

    cfg = SpatialMujocoConfig.quick(seed) if quick else SpatialMujocoConfig(seed=seed)
    s = spatial_mujoco(out, cfg, backend=ctx["backend"], progress=ctx.get("progress"))
    rows: list[Row] = []
    for name, t in s["tasks"].items():
        rows += [
            (
                f"{name}: MuJoCo grasps / kinematic grasps, same worlds",
                f"{t['successes']} / {t['kinematic_successes']} of {t['trials']}",
                "expected to extend to spatial objects (Discussion, no experiment)",
            ),
            (
                f"{name}: CRMs per world, MuJoCo / kinematic",
                f"{t['mean_crms_mujoco']} / {t['mean_crms_kinematic']}",
                "-",
            ),
            (f"{name}: random CRMs with the kinematic error flag", t["random_crms_same_error_as_kinematic"], "-"),
        ]
    sec = s["crm_seconds"]
    return s, [
        *rows,
        _sensing_row(s),
        ("MuJoCo 3-D wall time per CRM, median / max", f"{sec['median']} / {sec['max']} s", "-"),
    ]


def _physics_learning(out: Path, seed: int, quick: bool, ctx: dict[str, Any]) -> tuple[dict[str, Any], list[Row]]:
    from crmgrasp.experiments.physics_learning import PhysicsLearningConfig, physics_learning

    cfg = PhysicsLearningConfig.quick(seed) if quick else PhysicsLearningConfig(seed=seed)
    s = physics_learning(out, cfg, progress=ctx.get("progress"), jobs=ctx.get("jobs", 1))
    rows: list[Row] = []
    for name, t in s["tasks"].items():
        cells = []
        for way in ("transferred", "scratch", "fine-tuned"):
            w = t[way]
            cells.append(f"{way} {w['success']:.1%} ({w['crms']} CRMs, {w['mujoco_episodes']} MuJoCo episodes)")
        rows.append((f"{name}: true success on MuJoCo, {t['seeds']} seeds", "; ".join(cells), "-"))
    sec = s["mujoco_episode_seconds"]
    rows.append(("MuJoCo training episode, median / max wall time", f"{sec['median']} / {sec['max']} s", "-"))
    return s, rows


def _share(value: float | None) -> str:
    """A share as a percentage, or "-" where there is none."""
    return "-" if value is None else f"{value:.0%}"


def _third_contact(out: Path, seed: int, quick: bool, ctx: dict[str, Any]) -> tuple[dict[str, Any], list[Row]]:
    from crmgrasp.experiments.third_contact import ThirdContactConfig, third_contact

    cfg = ThirdContactConfig.quick(seed) if quick else ThirdContactConfig(seed=seed)
    s = third_contact(out, cfg, progress=ctx.get("progress"))
    by = {(r["family"], r["mu_goal"], r["fingers"]): r for r in s["rows"]}
    rows: list[Row] = []
    for fam, mu, _ in sorted(k for k in by if k[2] == 2):
        two, three = by[(fam, mu, 2)], by[(fam, mu, 3)]
        rows.append(
            (
                f"{fam}, mu_goal {mu:g}: graspable starts, two / three fingers; three-finger optimum / "
                f"{cfg.preset} preset, CRMs; friction of its final grasps (median); its worlds grasped on MuJoCo",
                f"{two['graspable_share']:.0%} / {three['graspable_share']:.0%}; {fmt(three['belief_optimum'])} / "
                f"{fmt(three['learned_crms'])}; {fmt(three['final_friction'])}; {_share(three['mujoco_success'])}",
                "more than two contacts 'with little modification' (Introduction, no experiment)",
            )
        )
    return s, rows


def _continuous_offsets(out: Path, seed: int, quick: bool, ctx: dict[str, Any]) -> tuple[dict[str, Any], list[Row]]:
    from crmgrasp.experiments.continuous_offsets import ContinuousOffsetsConfig, continuous_offsets

    cfg = ContinuousOffsetsConfig.quick(seed) if quick else ContinuousOffsetsConfig(seed=seed)
    s = continuous_offsets(out, cfg, progress=ctx.get("progress"))
    rows: list[Row] = []
    for name in cfg.tasks:
        mine = [r for r in s["rows"] if r["task"] == name]
        hand = next(r for r in mine if r["grid"] is None)
        best = min((r for r in mine if r["grid"] is not None), key=lambda r: (r["belief_optimum"], r["actions"]))
        learned = [r["greedy_mean"] for r in s["learned"] if r["task"] == name]
        rows.append(
            (
                f"{name}: optimum, hand-picked CRMs / best grid (offsets per pair); model-vi on the hand-picked "
                "CRMs / on a grid, refine-vi choosing its offsets, CRMs",
                f"{fmt(hand['belief_optimum'])} / {fmt(best['belief_optimum'])} ({best['offsets_per_pair']}); "
                + " / ".join(fmt(v) for v in learned),
                "A = C x C x [-r_max, r_max], four CRMs picked by hand (Sec. III, no experiment)",
            )
        )
    return s, rows


EXPERIMENTS: dict[str, tuple[str, Runner]] = {
    "figure4": ("Fig. 4: min-friction histogram of 30 opposition CRMs under sensing noise", _figure4),
    "figure7": ("Fig. 7: CRMs per episode vs episode, 20 trials, SARSA and the other learners", _figure7),
    "figure8": ("Fig. 8: the learned strategies on aliased and far-from-corner starts", _figure8),
    "figure9": ("Fig. 9: the learned policy, 11 noisy trials, in the (rho, moment) plane", _figure9),
    "compare": ("Every method on paper-box: learners, baselines, grasp controller, exact references", _compare),
    "figure7-sensitivity": (
        "Fig. 7 under each paper-consistent reading (starts, grasp reward, Q0, k): plateau, optimum, episodes",
        _sensitivity,
    ),
    "cost-of-failure": (
        "Discussion: an extra cost for errored CRMs (0-30) on notch-or-box and box-family; errors, sense-first and "
        "prepare-first shares",
        _cost_of_failure,
    ),
    "generalization": (
        "Discussion: one policy per object family, on held-out objects and sizes out of range",
        _generalization,
    ),
    "non-convex": ("Introduction: a U handle (non-convex), the learned strategy drawn like Fig. 8", _non_convex),
    "spatial": (
        "Discussion: 3-D CRMs on boxes and cups on a table, SARSA and model-vi against the references",
        _spatial,
    ),
    "third-contact": (
        "Introduction: two fingers against three on triangles, odd regular polygons, boxes, discs and cups in 3-D, "
        "friction 0.15 and 0.05",
        _third_contact,
    ),
    "continuous-offsets": (
        "Sec. III: the optimum over grids of offsets against the hand-picked CRMs, model-vi on each and "
        "refine-vi choosing its offsets",
        _continuous_offsets,
    ),
    "figure4-mujoco": ("Fig. 4 on the MuJoCo stand-in hand, and intrinsic contact sensing accuracy", _figure4_mujoco),
    "figure9-mujoco": ("Fig. 9 on the MuJoCo stand-in: the kinematic policy transferred, 11 trials", _figure9_mujoco),
    "spatial-mujoco": (
        "Discussion in 3-D on the MuJoCo stand-in: the spatial policies on cups and boxes free on a table, 20 worlds",
        _spatial_mujoco,
    ),
    "physics-learning": (
        "Learning on the MuJoCo stand-in: transferred, from scratch and fine-tuned on paper-box, box-family, cup-3d",
        _physics_learning,
    ),
}
"""Experiment name -> (description, runner(out_dir, seed, quick, context))."""

QUICK_BUDGETS = {
    "figure7": ("5 trials x 300 episodes", ("paper SARSA", "best learner", "SARSA k=0")),
    "compare": ("5 trials x 300 episodes", ("best learner",)),
    "figure7-sensitivity": ("20 trials x 300 episodes, 1 seed", ("",)),
    "cost-of-failure": ("3 trials x 150 episodes, 120 worlds", ("error cost",)),
    "generalization": ("2 trials x 100 episodes, 2 families", ("box", "cup")),
    "non-convex": ("2 trials x 150 episodes", ("U handle",)),
    "spatial": ("2 trials x 300 / 150 episodes, 80 / 40 worlds", ("box-3d", "cup-3d")),
    "third-contact": ("20 starts, triangles at 0.15 only, 1 trial x 200 episodes", ("triangles",)),
    "continuous-offsets": ("30 starts, grids 4, 5, 9, 2 trials x 200 episodes, 2 tasks", ("paper-box", "u-handle")),
    "spatial-mujoco": ("1 trial x 300 episodes, 4 worlds per task", ("cup-3d", "box-3d")),
    "physics-learning": ("1 seed, 5 MuJoCo / 100 kinematic episodes, 3 scoring episodes", ("paper-box", "box", "cup")),
}
"""Experiments whose learned numbers ``--quick`` computes on a smaller budget: that
budget, and the first words of the quantities that depend on it."""

GROUPS = (
    ("compare",),
    ("figure7-sensitivity",),
    ("cost-of-failure", "non-convex"),
    ("third-contact",),
    ("continuous-offsets",),
    ("generalization",),
    ("spatial",),
    ("spatial-mujoco",),
    ("physics-learning",),
    ("figure7", "figure8", "figure9", "figure9-mujoco"),
    ("figure4", "figure4-mujoco"),
)
"""Experiments that run in one process, in this order, when ``reproduce`` runs groups in
parallel (Figures 8 and 9 execute Figure 7's policy); longest expected group first."""

NEEDS_MUJOCO = ("figure4-mujoco", "figure9-mujoco", "spatial-mujoco", "physics-learning")
"""The experiments that need the extra ``crmgrasp[mujoco]`` (skipped without it)."""

IMAGES = {
    "figure4": ["figure4.png"],
    "figure7": ["figure7.png", "figure7_greedy.png", "figure7_k_ablation.png"],
    "figure8": ["figure8.png", "figure8.gif"],
    "figure9": ["figure9.png"],
    "compare": ["compare.png"],
    "figure7-sensitivity": ["figure7_sensitivity.png", "figure7_mechanism.png"],
    "cost-of-failure": ["cost_of_failure.png"],
    "generalization": ["generalization.png"],
    "non-convex": ["non_convex.png", "non_convex.gif"],
    "spatial": ["spatial.png", "spatial_strategy.png", "spatial_strategy.gif"],
    "third-contact": ["third_contact.png"],
    "continuous-offsets": ["continuous_offsets.png"],
    "figure4-mujoco": ["figure4_mujoco.png"],
    "figure9-mujoco": ["figure9_mujoco.png", "figure9_mujoco.gif"],
    "spatial-mujoco": ["spatial_mujoco.png", "spatial_mujoco.gif"],
    "physics-learning": ["physics_learning.png"],
}
