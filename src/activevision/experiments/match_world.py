"""What ``match.csv`` records of the world its strategies were scored in, beside the scores
(:mod:`activevision.experiments.match`), and how ``report.md`` words what differs from the
default world: the head's moves, the other robots, the detector, the walk, the ball, the
tick, the camera, any other ``--set`` field and the kidnapping."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass

from activevision.envs.match.config import MatchConfig
from activevision.typecheck import config_to_dict


def _float_text(value: str) -> str:
    return f"{float(value):g}"


@dataclass(frozen=True)
class WorldColumn:
    """A ``match.csv`` column recording one setting of the world the strategies were scored
    in: ``read`` takes it from the MatchConfig, ``meaning`` says what it is (and its unit),
    ``phrase`` words a value other than the default's for ``report.md`` (from the CSV's
    text)."""

    read: Callable[[MatchConfig], object]
    meaning: str
    phrase: Callable[[str], str]


#: ``match.csv``'s world columns after ``action_type, step_deg, robots, detect_near,
#: detect_far, false_detections`` (the head's moves, the other robots' count, the detector):
#: how our robot walks, the other robots' speed, the ball, the tick, the ball detector.
#: ``report.md`` names those that differ from ``MatchConfig()``'s.
WORLD_COLUMNS: dict[str, WorldColumn] = {
    "walk": WorldColumn(
        lambda c: c.walk.target,
        "where our robot walks: waypoints or ball (--walk; walk.target)",
        lambda v: f"our robot walking to the {v}",
    ),
    "walk_speed": WorldColumn(
        lambda c: c.walk.speed,
        "our robot's forward speed, m/s (walk.speed)",
        lambda v: f"our robot walking at {_float_text(v)} m/s",
    ),
    "turn_rate": WorldColumn(
        lambda c: c.walk.turn_rate,
        "our robot's turn rate, rad/s (walk.turn_rate)",
        lambda v: f"our robot turning at {_float_text(v)} rad/s",
    ),
    "robot_speed": WorldColumn(
        lambda c: c.others.speed,
        "the other robots' walking speed, m/s; 0: they stand (--robot-speed; others.speed)",
        lambda v: f"the other robots walking at {_float_text(v)} m/s",
    ),
    "ball_decel": WorldColumn(
        lambda c: c.ball.deceleration,
        "the ball's rolling deceleration, m/s^2 (ball.deceleration)",
        lambda v: f"the ball slowing by {_float_text(v)} m/s²",
    ),
    "kick_rate": WorldColumn(
        lambda c: c.ball.kick_rate,
        "kicks per tick (ball.kick_rate)",
        lambda v: f"{_float_text(v)} kicks per tick",
    ),
    "kick_speed": WorldColumn(
        lambda c: "-".join(f"{v:g}" for v in c.ball.kick_speed),
        "a kick's initial speed, m/s, uniform LOW-HIGH (ball.kick_speed)",
        lambda v: f"kicks of {v} m/s",
    ),
    "bounce_us": WorldColumn(
        lambda c: c.ball.bounces_off_own_robot,
        "the ball bounces off our robot too, True/False (--ball-bounces-off-us;"
        " ball.bounces_off_own_robot)",
        lambda v: (
            "the ball bouncing off our robot"
            if v == "True"
            else "the ball rolling through our robot"
        ),
    ),
    "restitution": WorldColumn(
        lambda c: c.others.ball_restitution,
        "the share of its speed towards a robot the ball keeps in a bounce"
        " (others.ball_restitution)",
        lambda v: f"the ball keeping {_float_text(v)} of its speed off a robot",
    ),
    "tick_s": WorldColumn(
        lambda c: c.tick_seconds,
        "seconds a tick (tick_seconds)",
        lambda v: f"ticks of {_float_text(v)} s",
    ),
    "ball_noise": WorldColumn(
        lambda c: c.detection.ball_noise,
        "the ball detector's noise, a fraction of the ball's range (detection.ball_noise)",
        lambda v: f"ball detections off by {_float_text(v)} of their range",
    ),
    # the camera: a run trained for a robot's own plays its matches through it
    "camera_px": WorldColumn(
        lambda c: f"{c.camera.width}x{c.camera.height}",
        "the camera's image, WIDTHxHEIGHT px (camera.width, camera.height)",
        lambda v: f"a {v} px camera",
    ),
    "hfov_deg": WorldColumn(
        lambda c: round(math.degrees(c.camera.hfov), 4),
        "the camera's horizontal field of view, degrees (camera.hfov, in rad)",
        lambda v: f"a {_float_text(v)}° field of view",
    ),
    "camera_height": WorldColumn(
        lambda c: c.camera.camera_height,
        "the camera's height above the carpet, m (camera.camera_height)",
        lambda v: f"the camera {_float_text(v)} m high",
    ),
    "head_range_deg": WorldColumn(
        lambda c: " ".join(
            f"{math.degrees(low):.4g}..{math.degrees(high):.4g}"
            for low, high in (
                (c.camera.pan_min, c.camera.pan_max),
                (c.camera.tilt_min, c.camera.tilt_max),
            )
        ),
        "the head's pan and tilt ranges, degrees, PAN_LOW..PAN_HIGH TILT_LOW..TILT_HIGH"
        " (camera.pan_min ... camera.tilt_max, in rad)",
        lambda v: f"the head panning {v.split()[0]}° and tilting {v.split()[-1]}°",
    ),
}


#: the MatchConfig fields that ``match.csv``'s other columns record (``camera.*`` and
#: ``kidnap.*`` too)
_RECORDED = frozenset(
    {
        "ticks",
        "action_type",
        "step_deg",
        "max_move_deg",
        "robots.count",
        "detection.near",
        "detection.far",
        "detection.false_rate",
        "detection.ball_noise",
        "walk.target",
        "walk.speed",
        "walk.turn_rate",
        "others.speed",
        "others.ball_restitution",
        "ball.deceleration",
        "ball.kick_rate",
        "ball.kick_speed",
        "ball.bounces_off_own_robot",
        "tick_seconds",
    }
)


def other_settings(config: MatchConfig) -> str:
    """The fields of ``config`` that differ from ``MatchConfig()``'s and that no other
    ``match.csv`` column records, as ``activevision match --set`` takes them
    (``tracker.gate=9.21 walk.reach=0.5``; values JSON); empty where there are none."""

    def leaves(values: dict[str, object], prefix: str = "") -> dict[str, object]:
        flat: dict[str, object] = {}
        for key, value in values.items():
            if isinstance(value, dict):
                flat.update(leaves(value, f"{prefix}{key}."))
            else:
                flat[f"{prefix}{key}"] = value
        return flat

    mine, default = leaves(config_to_dict(config)), leaves(config_to_dict(MatchConfig()))
    return " ".join(
        f"{path}={json.dumps(value, separators=(',', ':'))}"
        for path, value in mine.items()
        if value != default[path]
        and path not in _RECORDED
        and not path.startswith(("camera.", "kidnap."))
    )


def world_columns(config: MatchConfig) -> dict[str, object]:
    """``match.csv``'s world columns of ``config``: the head's moves, the other robots, the
    detector, then :data:`WORLD_COLUMNS`, then ``settings`` (:func:`other_settings`) where
    there are any (a default world's file has no such column)."""
    settings = other_settings(config)
    return {
        "action_type": config.action_type,
        "step_deg": (  # the most the head moves per tick and axis
            config.step_deg if config.action_type == "discrete" else max(config.max_move_deg)
        ),
        "robots": "-".join(str(n) for n in sorted(set(config.robots.count))),
        "detect_near": config.detection.near,
        "detect_far": config.detection.far,
        "false_detections": config.detection.false_rate,
        **{name: column.read(config) for name, column in WORLD_COLUMNS.items()},
        **({"settings": settings} if settings else {}),
        **(kidnap_columns(config) if config.kidnap.enabled else {}),
    }


def kidnap_columns(config: MatchConfig) -> dict[str, object]:
    """``match.csv``'s record of the kidnapping (``MatchConfig.kidnap``), written where it
    is on: per minute, the ticks named, how far (m, LOW-HIGH) and how much it turns (rad)."""
    kidnap = config.kidnap
    return {
        "kidnap_rate": kidnap.rate,
        "kidnap_ticks": " ".join(str(t) for t in kidnap.ticks),
        "kidnap_distance": "-".join(f"{v:g}" for v in kidnap.distance),
        "kidnap_turn": kidnap.turn,
    }


def kidnap_text(config: MatchConfig) -> str:
    """The kidnapping in words: ``"kidnapped 1/min and in tick 200, carried 1-2 m, turned up
    to 0.8 rad"``; empty where it is off."""
    kidnap = config.kidnap
    if not kidnap.enabled:
        return ""
    when = [f"{kidnap.rate:g}/min"] if kidnap.rate else []
    if kidnap.ticks:
        ticks = ", ".join(str(t) for t in kidnap.ticks)
        when.append(f"in tick{'s' if len(kidnap.ticks) > 1 else ''} {ticks}")
    low, high = kidnap.distance
    return (
        f"kidnapped {' and '.join(when)}, carried {low:g}-{high:g} m, turned up to"
        f" {kidnap.turn:g} rad"
    )


def world_differences(row: dict[str, str]) -> list[str]:
    """The phrases of a ``match.csv`` row's :data:`WORLD_COLUMNS` whose value is not the
    default world's (``MatchConfig()``), in column order; none for a file written before
    they were recorded."""
    defaults = world_columns(MatchConfig())
    phrases = []
    for name, column in WORLD_COLUMNS.items():
        value = row.get(name)
        if value is None or value == "" or _same_text(value, str(defaults[name])):
            continue
        phrases.append(column.phrase(value))
    if row.get("settings"):
        phrases.append(f"--set {row['settings']}")
    if row.get("kidnap_rate") not in (None, ""):
        ticks = row.get("kidnap_ticks") or ""
        when = [f"{_float_text(row['kidnap_rate'])}/min"] if float(row["kidnap_rate"]) else []
        when += [f"in ticks {ticks}"] if ticks else []
        phrases.append(
            f"our robot kidnapped {' and '.join(when)}, carried {row.get('kidnap_distance')} m,"
            f" turned up to {_float_text(row.get('kidnap_turn') or '0')} rad"
        )
    return phrases


def _same_text(a: str, b: str) -> bool:
    """Two CSV cells alike: equal numbers (``0.20`` and ``0.2``), else equal text."""
    try:
        return float(a) == float(b)
    except ValueError:
        return a == b
