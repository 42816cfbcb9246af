"""Type checks for configuration dataclasses, driven by their annotations.

Configs arrive from Python callers, ``gymnasium.make`` keywords and JSON files; a wrong type
should fail at construction with one message naming the field and the value, not as a deep
traceback (or a silently wrong episode) later. :func:`check_dataclass_fields` checks every
field against its annotation and stores a normalised value (``3`` for a float field becomes
``3.0``, a JSON list for a tuple field becomes a tuple).

A leaf module: it imports nothing from activevision, so every subpackage's config may use it.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import numbers
import types
import typing
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Literal, TypeVar

import numpy as np

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

#: ``dataclasses.field(metadata=ALLOW_NONFINITE)``: the field's floats may be NaN or infinite.
ALLOW_NONFINITE: Mapping[str, bool] = types.MappingProxyType({"finite": False})


class _Mismatch(Exception):
    """Internal: a value does not fit a type (the caller words the message)."""

    def __init__(self, nonfinite: bool = False) -> None:
        super().__init__()
        self.nonfinite = nonfinite  #: the type fits, but a float is NaN or infinite


@functools.cache
def _field_types(cls: type) -> dict[str, Any]:
    # get_type_hints resolves string annotations (``from __future__ import annotations``);
    # cached because configs are built often (``EnvConfig.replace``) and the hints never change.
    return typing.get_type_hints(cls)


def check_dataclass_fields(instance: Any) -> None:
    """Check every field of dataclass ``instance`` against its annotation and store the
    normalised value (frozen dataclasses too).

    Supported annotations: ``bool`` (not an int), ``int`` (not a bool), ``float`` (ints and
    other real numbers accepted, converted to float, finite unless the field's metadata is
    :data:`ALLOW_NONFINITE`), ``str``, ``Literal[...]``, ``tuple[X, Y]`` and ``tuple[X, ...]``
    (lists accepted), ``X | None`` and other unions, ``Any``, and classes (dataclasses
    included), which need an instance.

    Raises:
        ValueError: ``"{Class}.{field}: expects {type}, got {value!r}"`` for the first field
            that does not fit.
    """
    cls: type = type(instance)
    hints = _field_types(cls)
    for f in dataclasses.fields(instance):
        value = getattr(instance, f.name)
        hint = hints[f.name]
        finite = f.metadata.get("finite", True)
        try:
            normalised = _check(value, hint, finite)
        except _Mismatch as e:
            wanted = describe(hint) + (" with finite values" if e.nonfinite else "")
            raise ValueError(f"{cls.__name__}.{f.name}: expects {wanted}, got {value!r}") from None
        if normalised is not value:
            object.__setattr__(instance, f.name, normalised)  # frozen dataclasses too
        why = _out_of_range(normalised, f.metadata)
        if why:
            raise ValueError(f"{cls.__name__}.{f.name}: must be {why}, got {value!r}")


def in_range(
    low: float | None = None,
    high: float | None = None,
    *,
    low_open: bool = False,
    high_open: bool = False,
) -> Mapping[str, Any]:
    """Field metadata that bounds a number: ``field(default=32, metadata=in_range(1))``.
    :func:`check_dataclass_fields` checks it after the type, so each field's range is
    written beside the field."""
    return types.MappingProxyType({"range": (low, high, low_open, high_open)})


def _out_of_range(value: Any, metadata: Mapping[str, Any]) -> str:
    """Why ``value`` breaks the field's :func:`in_range` bounds ("" when it does not)."""
    if "range" not in metadata:
        return ""
    low, high, low_open, high_open = metadata["range"]
    below = low is not None and (value <= low if low_open else value < low)
    above = high is not None and (value >= high if high_open else value > high)
    if not (below or above):
        return ""
    if low is not None and high is not None:
        return f"in {'(' if low_open else '['}{low}, {high}{')' if high_open else ']'}"
    if low is not None:
        return f"{'>' if low_open else '>='} {low}"
    return f"{'<' if high_open else '<='} {high}"


def config_to_dict(instance: Any) -> dict[str, Any]:
    """A (nested) config dataclass as plain JSON values: dataclass fields become objects,
    tuples lists."""

    def plain(value: Any) -> Any:
        if dataclasses.is_dataclass(value) and not isinstance(value, type):
            return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
        if isinstance(value, tuple | list):
            return [plain(v) for v in value]
        if isinstance(value, Mapping):
            return {k: plain(v) for k, v in value.items()}
        return value

    return typing.cast(dict[str, Any], plain(instance))


_Config = TypeVar("_Config", bound="DataclassInstance")


def config_from_dict(cls: type[_Config], values: Any, where: str = "") -> _Config:
    """Build config dataclass ``cls`` from :func:`config_to_dict`'s output, recursing into
    fields whose type is a dataclass (missing keys take their defaults). ValueError names an
    unknown key by its dotted path."""
    where = where or cls.__name__
    if not isinstance(values, Mapping):
        raise ValueError(f"{where}: expects an object of {cls.__name__} fields, got {values!r}")
    known = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(values) - known)
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {unknown}; known: {sorted(known)}")
    return cls(**nested_configs(cls, values, where))


def nested_configs(cls: type, values: Mapping[str, Any], where: str = "") -> dict[str, Any]:
    """``values`` (keyword arguments of config dataclass ``cls``) with every object given for
    a field whose type is a dataclass built into that dataclass (:func:`config_from_dict`);
    other values, and names that are not fields, as they are. Gymnasium's
    ``EnvSpec.to_json`` writes an env's config keywords as such objects
    (``dataclasses.asdict``), so ``gymnasium.make(EnvSpec.from_json(...))`` reads them."""
    where = where or cls.__name__
    hints = _field_types(cls)
    known = {f.name for f in dataclasses.fields(cls)}
    out = dict(values)
    for name, value in values.items():
        hint = hints[name] if name in known else None
        if isinstance(hint, type) and dataclasses.is_dataclass(hint) and isinstance(value, Mapping):
            out[name] = config_from_dict(hint, value, f"{where}.{name}")
    return out


def _check(value: Any, hint: Any, finite: bool) -> Any:
    """``value`` normalised to ``hint``, or :class:`_Mismatch`."""
    origin = typing.get_origin(hint)
    if hint is Any or hint is object:
        return value
    if hint is type(None):
        return _require(value is None, value)
    if hint is bool:
        return bool(_require(_is_bool(value), value))
    if hint is int:
        return int(_require(_is_int(value), value))
    if hint is float:
        _require(is_real(value), value)
        number = float(value)
        if finite and not math.isfinite(number):
            raise _Mismatch(nonfinite=True)
        return number
    if origin is Literal:
        # type() too, so that True does not pass for Literal[1] (True == 1).
        return _require(any(value == a and type(value) is type(a) for a in hint.__args__), value)
    if origin is tuple:
        return _check_tuple(value, typing.get_args(hint), finite)
    if origin is typing.Union or origin is types.UnionType:
        return _check_union(value, typing.get_args(hint), finite)
    if isinstance(hint, type):
        return _require(isinstance(value, hint), value)
    if isinstance(origin, type):  # e.g. dict[str, float]: only the container is checked
        return _require(isinstance(value, origin), value)
    raise TypeError(f"check_dataclass_fields: unsupported annotation {hint!r}")


def _check_tuple(value: Any, args: tuple[Any, ...], finite: bool) -> tuple[Any, ...]:
    _require(isinstance(value, tuple | list), value)  # JSON has lists, not tuples
    if len(args) == 2 and args[1] is Ellipsis:
        args = (args[0],) * len(value)
    _require(len(value) == len(args), value)
    return tuple(_check(v, a, finite) for v, a in zip(value, args, strict=True))


def _check_union(value: Any, args: tuple[Any, ...], finite: bool) -> Any:
    nonfinite = False
    for arm in args:
        try:
            return _check(value, arm, finite)
        except _Mismatch as e:
            nonfinite |= e.nonfinite
    raise _Mismatch(nonfinite)


def _require(ok: bool, value: Any) -> Any:
    if not ok:
        raise _Mismatch
    return value


def _is_bool(value: Any) -> bool:
    # numpy booleans are neither bool nor numbers.Integral, so name them explicitly.
    return isinstance(value, bool | np.bool_)


def is_real(value: object) -> bool:
    """Whether ``value`` is a real number (NumPy's included), not a bool."""
    return isinstance(value, numbers.Real) and not _is_bool(value)


def _is_int(value: Any) -> bool:
    # numbers.Integral covers numpy integers; bool is an Integral too, but never a count.
    return isinstance(value, numbers.Integral) and not _is_bool(value)


def describe(hint: Any) -> str:
    """A short human name of a type annotation: ``float``, ``tuple[float, float]``,
    ``one of '8way', '4way'``, ``FieldSpec | None``."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if hint is type(None):
        return "None"
    if origin is Literal:
        return "one of " + ", ".join(repr(a) for a in args)
    if origin is typing.Union or origin is types.UnionType:
        return " | ".join(describe(a) for a in args)
    if origin is tuple:
        inner = ", ".join("..." if a is Ellipsis else describe(a) for a in args)
        return f"tuple[{inner}]"
    if isinstance(hint, type):
        return hint.__name__
    return repr(hint)


def replace_fields(instance: _Config, changes: Mapping[str, Any]) -> _Config:
    """A copy of dataclass ``instance`` with ``changes``; an unknown name is a ValueError
    naming the fields (the environments pass their keyword arguments here, and
    ``gymnasium.make`` rewords a TypeError into a long one)."""
    names = {f.name for f in dataclasses.fields(instance)}
    for name, value in changes.items():
        if name not in names:
            raise ValueError(
                f"{type(instance).__name__}: unknown keyword {name}={value!r};"
                f" the fields are {sorted(names)}"
            )
    return dataclasses.replace(instance, **changes)
