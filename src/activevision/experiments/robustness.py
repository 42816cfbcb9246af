"""The robustness suite: one policy scored on the same fixed-seed episodes under named
perturbations of the world it was trained in (``activevision robustness``).

The table (:func:`perturbations`):

* ``clean``: the policy's own training env, appearance and other robots as trained; every
  drop is measured against it. A policy trained with randomisation also gets
  ``paper-clean``: the same env with appearance neutral and no other robots (the paper's
  world).
* one row per appearance factor (:class:`~activevision.rendering.appearance.
  AppearanceConfig`) at a ``mild`` level, inside the robust training ranges
  (``AppearanceConfig.randomised()``), and a ``strong`` one beyond them (what randomised
  training did not see); gain, offset and line width in both directions. Each level is a
  fixed range ``(v, v)``, so every episode sees exactly ``v``.
* ``robots-1`` ... ``robots-4``: that many other robots, occluding landmarks.
* ``mount-tilt+4deg``, ``mount-height+5cm``, ``mount-fov+10%``: the camera mounted
  differently from the model the robot (and the policy's env) assumes; only the image
  changes.
* ``all-mild`` and ``all-mild+robots-4``: every appearance factor at its mild level at once
  (gain and offset dark, lines thin: a dim hall), alone and with four other robots. A real
  camera is off in every way at once; these rows show whether mild changes add up.

**One factor a row** (but the two ``all-mild`` rows). Every perturbation row is built on
the *neutral* env of the policy: its training env with every appearance factor neutral and
no other robots (the ``paper-clean`` env; for a policy trained on the clean world that is
``clean`` itself), then the row's one factor set. So a row measures that factor alone,
never mixed with the randomisation the policy trained under; for a randomised policy its
drop vs ``clean`` includes the (usually small) change from the trained mix to the neutral
world, which the ``paper-clean`` row shows on its own.

**Same seeds.** Every row plays episodes ``episode_seed(seed, 0..n-1)``. The look is drawn
after the start, so appearance rows play the very starts of the robot-free ``paper-clean``
world (which are ``clean``'s for a policy trained without other robots); other robots are
drawn within the start (a start whose goal a robot hides is drawn again), so rows with
robots (``robots-*``, ``all-mild+robots-4``, and ``clean`` where the policy trained with
them) share the seeds, not always the starts.

``in_training_range``: every drawn range of the row lies within the policy's training
ranges (appearance and robot count); ``in_robust_range``: within the robust ranges
(:data:`ROBUST_APPEARANCE`, :data:`ROBUST_ROBOTS`, those of the ``dagger_robust`` preset).
A row's world is built on the policy's own clean world (for the shipped policy, its
randomised training world). ``--list`` (:func:`list_table`) alone builds every row on the
paper's default world; with a policy named (``--run``, ``--shipped``, ``--method``) it builds
them on that policy's world, as the CSV does, and adds its training range.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from activevision.envs import ActiveVisionEnv, EnvConfig
from activevision.experiments.evaluate import Interval, evaluate_policy
from activevision.experiments.policies import HeadPolicy, LearnedPolicy, OnnxPolicy
from activevision.rendering.appearance import FACTORS, AppearanceConfig

#: The robust training ranges (the ``dagger_robust`` preset's appearance and robot count).
ROBUST_APPEARANCE = AppearanceConfig.randomised()
ROBUST_ROBOTS = (0, 4)
#: The stripe width of the stripes rows (m; the stripes' amplitude is the factor).
STRIPE_WIDTH = 0.75

#: (factor, direction, mild, strong): mild inside :data:`ROBUST_APPEARANCE`, strong beyond.
APPEARANCE_LEVELS: tuple[tuple[str, str, float, float], ...] = (
    ("gain", "dark", 0.75, 0.45),
    ("gain", "bright", 1.3, 1.8),
    ("offset", "dark", -15.0, -45.0),
    ("offset", "bright", 15.0, 45.0),
    ("gamma", "", 1.3, 1.8),
    ("vignetting", "", 0.3, 0.7),
    ("read_noise", "", 4.0, 15.0),
    ("shot_noise", "", 0.4, 2.0),
    ("defocus", "", 0.8, 2.5),
    ("motion_blur", "", 0.3, 0.9),
    ("stripes", "", 8.0, 30.0),
    ("grain", "", 6.0, 25.0),
    ("line_width", "thin", -0.01, -0.025),
    ("line_width", "thick", 0.015, 0.04),
    ("line_wear", "", 0.35, 0.8),
    ("clutter", "", 40.0, 110.0),
)
#: (name, factor, value): the camera mounted off the robot's model (beyond the robust ranges)
MOUNT_LEVELS: tuple[tuple[str, str, float], ...] = (
    ("mount-tilt+4deg", "mount_tilt_deg", 4.0),
    ("mount-height+5cm", "mount_height", 0.05),
    ("mount-fov+10%", "mount_fov", 0.10),
)
ROBOT_COUNTS = (1, 2, 3, 4)
#: (name, other robots): the rows with every factor of APPEARANCE_LEVELS at its mild level
#: (a factor with two directions at its first: dark, thin)
ALL_MILD_LEVELS: tuple[tuple[str, int], ...] = (("all-mild", 0), ("all-mild+robots-4", 4))
ALL = "all"

CLEAN = "clean"
PAPER_CLEAN = "paper-clean"


@dataclass(frozen=True)
class Perturbation:
    """A named change of the policy's env: ``factor`` (an AppearanceConfig field,
    ``"robots"``, or ``"none"`` for the two clean rows) set to ``value``; or ``factor``
    ``"all"``: every factor at its mild level and ``value`` other robots."""

    name: str
    factor: str
    level: str  #: "trained", "neutral", "mild", "strong", or the robot count
    value: float | None = None

    @property
    def image_only(self) -> bool:
        """Whether the row changes the camera image alone (an appearance factor, the camera
        mount, ``all-mild``): the episodes, goals and hidden landmarks stay ``paper-clean``'s,
        so a method that does not see the image plays it exactly as it plays that world."""
        return self.factor in FACTORS or (self.factor == ALL and not self.value)

    @property
    def setting(self) -> str:
        """The row's setting as text (``gain=0.45``, ``robots=2``, ``as trained``)."""
        if self.factor == ALL:
            return "all factors mild" + (f", robots={self.value:g}" if self.value else "")
        if self.value is None:
            return "as trained" if self.name == CLEAN else "neutral"
        return f"{self.factor}={self.value:g}"

    def config(self, clean: EnvConfig) -> EnvConfig:
        """The env of this row for a policy trained on ``clean``."""
        if self.name == CLEAN:
            return clean
        base = neutral_config(clean)
        if self.value is None:
            return base
        if self.factor == "robots" or self.factor == ALL:
            k = int(self.value)
            base = base.replace(robots=dataclasses.replace(clean.robots, count=(k, k)))
            if self.factor == "robots":
                return base
            levels: dict[str, float] = {}
            for factor, _, mild, _ in APPEARANCE_LEVELS:
                levels.setdefault(factor, mild)  # the first direction of each factor
        else:
            levels = {self.factor: self.value}
        changes = {factor: (v, v) for factor, v in levels.items()}
        if "stripes" in levels:
            changes["stripe_width"] = (STRIPE_WIDTH, STRIPE_WIDTH)
        return base.replace(appearance=AppearanceConfig().replace(**changes))


def neutral_config(clean: EnvConfig) -> EnvConfig:
    """``clean`` with every appearance factor neutral and no other robots."""
    return clean.replace(
        appearance=AppearanceConfig(), robots=dataclasses.replace(clean.robots, count=(0, 0))
    )


def _all_perturbations() -> tuple[Perturbation, ...]:
    rows = [Perturbation(CLEAN, "none", "trained"), Perturbation(PAPER_CLEAN, "none", "neutral")]
    for factor, direction, mild, strong in APPEARANCE_LEVELS:
        stem = factor.replace("_", "-") + (f"-{direction}" if direction else "")
        rows.append(Perturbation(f"{stem}-mild", factor, "mild", mild))
        rows.append(Perturbation(f"{stem}-strong", factor, "strong", strong))
    rows += [Perturbation(f"robots-{k}", "robots", str(k), float(k)) for k in ROBOT_COUNTS]
    rows += [Perturbation(name, factor, "strong", v) for name, factor, v in MOUNT_LEVELS]
    rows += [Perturbation(name, ALL, "mild", float(k)) for name, k in ALL_MILD_LEVELS]
    return tuple(rows)


PERTURBATIONS: tuple[Perturbation, ...] = _all_perturbations()


def perturbation_names() -> tuple[str, ...]:
    """Every perturbation's name, in table order."""
    return tuple(p.name for p in PERTURBATIONS)


def is_randomised(config: EnvConfig) -> bool:
    """Whether ``config`` trains with randomised appearance or other robots."""
    return config.appearance.enabled or config.robots.max_count > 0


def perturbations(
    clean: EnvConfig, names: Sequence[str] | None = None, blind: str | None = None
) -> tuple[Perturbation, ...]:
    """The rows to play for a policy trained on ``clean``: ``names`` (default: all) in table
    order, always with ``clean`` first (the reference of every drop); ``paper-clean`` by
    default only when ``clean`` is randomised (otherwise it is ``clean`` again).

    ``blind``: the name of a method that does not see the camera image (it plays from the
    env's state): the rows that change the image alone (:attr:`Perturbation.image_only`)
    would score it exactly as ``paper-clean`` and read as robustness, so they are left out
    by default and a ValueError when named."""
    known = perturbation_names()
    for name in names or ():
        if name not in known:
            raise ValueError(f"unknown perturbation {name!r}; choose from {', '.join(known)}")
    unseen = {p.name for p in PERTURBATIONS if blind is not None and p.image_only}
    if names:
        named = [name for name in names if name in unseen]
        if named:
            raise ValueError(
                f"--perturbations {' '.join(named)}: {'changes' if len(named) == 1 else 'change'}"
                f" only the camera image, which"
                f" {blind} does not see (it plays from the env's state); score a policy that"
                " sees it (--run, --shipped) or choose rows with other robots"
            )
        wanted = {CLEAN, *names}
        return tuple(p for p in PERTURBATIONS if p.name in wanted)
    return tuple(
        p
        for p in PERTURBATIONS
        if (p.name != PAPER_CLEAN or is_randomised(clean)) and p.name not in unseen
    )


def sees_image(policy: HeadPolicy) -> bool:
    """Whether ``policy`` reads the camera image (a trained network); the built-in
    baselines (entropy methods, oracle, scan, random) play from the env's state. They were
    not trained either, so they have no training range (:data:`NO_TRAINING_RANGE`)."""
    return isinstance(policy, (LearnedPolicy, OnnxPolicy))


def within(config: EnvConfig, trained: EnvConfig) -> bool:
    """Whether every range ``config`` draws from lies within ``trained``'s: each appearance
    factor (the stripe width only where stripes are on) and the robot count."""
    for name in FACTORS:
        if name == "stripe_width" and config.appearance.stripes == (0.0, 0.0):
            continue
        lo, hi = getattr(config.appearance, name)
        t_lo, t_hi = getattr(trained.appearance, name)
        if not t_lo <= lo <= hi <= t_hi:
            return False
    (lo, hi), (t_lo, t_hi) = config.robots.count, trained.robots.count
    return t_lo <= lo <= hi <= t_hi


def robust_config(clean: EnvConfig) -> EnvConfig:
    """``clean`` at the robust training ranges."""
    return clean.replace(
        appearance=ROBUST_APPEARANCE,
        robots=dataclasses.replace(clean.robots, count=ROBUST_ROBOTS),
    )


#: The CSV's metrics: column name -> :data:`~activevision.experiments.evaluate.METRICS` key.
SCORES = {"success_rate": "success_rate", "goal_reached": "success"}


def score_perturbations(
    policy: HeadPolicy,
    clean: EnvConfig,
    rows: Sequence[Perturbation],
    episodes: int,
    seed: int,
    progress: Callable[[dict[str, Any]], None] | None = None,
    trained: bool | None = None,
) -> list[dict[str, Any]]:
    """Play ``policy`` on ``episodes`` fixed-seed episodes under each of ``rows`` (its
    ``clean`` row first); one flat dict a row (the CSV's columns), with each metric's
    mean, 95% interval and drop vs ``clean`` in percentage points. ``progress`` is called
    with each row as it is done. A method that was not ``trained`` (default: whether it
    :func:`sees_image`, as the built-in baselines do not) has no training range: its rows'
    ``in_training_range`` is None (empty in the CSV)."""
    if trained is None:
        trained = sees_image(policy)
    if not rows or rows[0].name != CLEAN:
        raise ValueError("the perturbations must start with 'clean' (the reference)")
    robust = robust_config(clean)
    out: list[dict[str, Any]] = []
    for p in rows:
        config = p.config(clean)
        env = ActiveVisionEnv(config)
        try:
            _, summary, _ = evaluate_policy(policy, episodes, seed, env=env)
        finally:
            env.close()
        row: dict[str, Any] = {
            "name": p.name,
            "factor": p.factor,
            "level": p.level,
            "setting": _setting(p, trained),
            "in_training_range": within(config, clean) if trained else None,
            "in_robust_range": within(config, robust),
            "n": episodes,
            "seed": seed,
        }
        for column, metric in SCORES.items():
            iv: Interval = summary[metric]
            row.update({column: iv.mean, f"{column}_low": iv.low, f"{column}_high": iv.high})
        for column in SCORES:
            reference = out[0][column] if out else row[column]
            row[f"{column}_drop_pts"] = 100.0 * (reference - row[column])
        out.append(row)
        if progress is not None:
            progress(row)
    return out


def _change(drop_pts: float) -> float:
    """A drop in points as the change vs clean, to 0.1 point (no ``-0.0``)."""
    return round(-drop_pts, 1) + 0.0


#: the ``setting`` of the clean row of a method that was not trained
UNTRAINED_CLEAN = "the env as it is"


def _setting(p: Perturbation, trained: bool) -> str:
    """The row's setting; an untrained method's clean row is the env it is scored in, not
    "as trained"."""
    return p.setting if trained or p.name != CLEAN else UNTRAINED_CLEAN


#: the ``trained`` / ``training range`` cell of a method that was not trained (scan, random,
#: the oracle, the entropy methods: they play from the env's state)
NO_TRAINING_RANGE = "— (untrained)"


def untrained(row: Mapping[str, Any]) -> bool:
    """Whether a scored row is of a method that was not trained (``in_training_range`` None
    as scored, or empty as read back from the CSV)."""
    return row["in_training_range"] in (None, "")


def format_row(row: dict[str, Any]) -> str:
    """One line of :func:`format_table`; a method that was not trained (:func:`untrained`)
    has "—" in the ``trained`` cell, not a yes or no."""

    def cell(column: str) -> str:
        return (
            f"{100 * row[column]:5.1f} [{100 * row[f'{column}_low']:5.1f},"
            f"{100 * row[f'{column}_high']:5.1f}] {_change(row[f'{column}_drop_pts']):+7.1f}"
        )

    trained = "—" if untrained(row) else "yes" if row["in_training_range"] else "no"
    return (
        f"{row['name']:<25}{row['setting']:<28}{trained:>7}  "
        f"{cell('success_rate')}   {cell('goal_reached')}"
    )


def table_header() -> str:
    """The two header lines of :func:`format_table` and a rule."""
    pad = " " * (25 + 28 + 7 + 2)
    groups = pad + f"{' success rate % ':-^27}   {' goal reached % ':-^27}"
    sub = f"{' mean [95% interval]   change':<27}"
    names = f"{'perturbation':<25}{'setting':<28}{'trained':>7}  {sub}   {sub}"
    return "\n".join([groups, names, "-" * len(names)])


def format_table(rows: Sequence[dict[str, Any]]) -> str:
    """The scored rows as a plain-text table: percent, and the change vs clean in points;
    ``trained``: whether the row lies within the policy's training ranges ("—" for a method
    that was not trained)."""
    return "\n".join([table_header(), *(format_row(r) for r in rows)])


def worst_drops(rows: Sequence[dict[str, Any]]) -> str:
    """One line: the largest drop of each metric vs clean and where."""
    others = [r for r in rows if r["name"] != CLEAN]
    if not others:
        return "only the clean row was played"
    parts = []
    for column, label in (("success_rate", "success rate"), ("goal_reached", "goal reached")):
        worst = max(others, key=lambda r: r[f"{column}_drop_pts"])
        drop = worst[f"{column}_drop_pts"]
        if drop > 0:
            parts.append(f"{label} {_change(drop):+.1f} pts ({worst['name']})")
        else:
            parts.append(f"{label}: no drop")
    return "worst change vs clean: " + ", ".join(parts)


def list_table(
    clean: EnvConfig | None = None, names: Sequence[str] | None = None, blind: str | None = None
) -> str:
    """The perturbations with their settings and whether each lies within the robust
    training ranges (``activevision robustness --list``): every one on the paper's default
    world, or, given a policy's ``clean`` world, the rows that ``names`` would play for it,
    built on that world, with whether each lies within its training ranges too (the CSV's
    ``in_training_range`` and ``in_robust_range``; ``blind``: as :func:`perturbations`).
    A ``blind`` method is a built-in baseline, never trained: its training range column
    says so (:data:`NO_TRAINING_RANGE`) instead of comparing with a world it never
    learnt in."""
    rows = PERTURBATIONS if clean is None else perturbations(clean, names, blind)
    world = clean or EnvConfig()
    robust = robust_config(world)
    if clean is None and names:
        rows = tuple(p for p in rows if p.name in set(names) | {CLEAN})
    header = f"{'perturbation':<25}{'factor':<16}{'level':<9}{'setting':<28}{'robust range':<14}"
    lines = [(header + ("training range" if clean is not None else "")).rstrip()]
    lines.append("-" * len(lines[0]))
    for p in rows:
        config = p.config(world)
        line = f"{p.name:<25}{p.factor:<16}{p.level:<9}{_setting(p, blind is None):<28}"
        line += f"{_yes_no(within(config, robust)):<14}"
        if clean is not None:
            line += NO_TRAINING_RANGE if blind is not None else _yes_no(within(config, clean))
        lines.append(line.rstrip())
    return "\n".join(lines)


def _yes_no(inside: bool) -> str:
    return "yes" if inside else "no (beyond)"
