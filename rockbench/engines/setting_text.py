"""THE grammar of engine settings written as text - the command line's ``--setting``, a
work-precision sweep's extra settings, a setting's label - with each value typed against the
backend's declared ``Settings`` (the type of the field's default:
:func:`rockbench.values.parse_value`), never guessed from the text.

* ``ENGINE.KEY=VALUE`` - one field of one engine's Settings (``pymunk.iterations=20``);
* ``KEY=VALUE`` - the same for the one engine selected (with several selected, the error names
  the form to use); a sweep's extra setting without an engine applies to every engine swept;
* ``ENGINE.KEY=VALUE,KEY2=VALUE2`` - several fields of one engine, one set of overrides (a
  sweep's extra setting; the bare fields after the first belong to its engine);
* ``ENGINE:KEY=VALUE,...`` - the spelling the Python API of ``tradeoff`` took before, read
  the same.

A set of fields is an :class:`Overrides` (the engine it belongs to, or None for every engine,
and its values): what crosses from the command line to the studies, with no sentinel key.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Iterable, Mapping

from ..errors import ParameterError
from ..values import parse_value

__all__ = ["Overrides", "setting_value", "parse_settings", "parse_overrides", "split_field"]


def _settings_class(engine: str) -> type:
    from . import get_backend

    return get_backend(engine).Settings


def setting_value(cls: type, name: str, raw: str, shown: str | None = None) -> Any:
    """``raw`` as the type of the Settings field ``name`` of ``cls`` (from its default); errors
    name ``shown`` (default ``--setting NAME``)."""
    shown = shown or f"--setting {name}"
    fields = {f.name: f for f in dataclasses.fields(cls)}
    if name not in fields:
        raise ParameterError(shown, raw, f"a field of {cls.__qualname__}: {', '.join(fields)}")
    f = fields[name]
    default = f.default if f.default is not dataclasses.MISSING else None
    try:
        return parse_value(raw, default)
    except ValueError:
        raise ParameterError(shown, raw, f"a value of type {type(default).__name__}") from None


def split_field(text: str, option: str = "--setting") -> tuple[str | None, str, str]:
    """``"ENGINE.KEY=VALUE"`` (or ``ENGINE:KEY=VALUE``, or a bare ``KEY=VALUE``) -> (engine or
    None, key, raw value), stripped; ENGINE must be a registered backend."""
    from ..registry import REGISTRY

    key, sep, raw = text.partition("=")
    key, raw = key.strip(), raw.strip()
    if not sep or not key:
        raise ParameterError(option, text, "ENGINE.KEY=VALUE (e.g. pymunk.iterations=20)")
    for mark in (".", ":"):
        head, dot, field = key.partition(mark)
        if dot:
            if head.strip() not in REGISTRY:
                raise ParameterError(option, text, f"ENGINE.KEY=VALUE with ENGINE one of "
                                                   f"{', '.join(REGISTRY)}")
            return head.strip(), field.strip(), raw
    return None, key, raw


def _selected(engine: str | None, text: str, field: str, raw: str, engines: list[str],
              selectable: list[str], option: str) -> str:
    """The engine a field written as ``text`` belongs to: its ENGINE, one of ``selectable``, or
    for a bare field the one engine of ``engines``."""
    if engine is not None:
        if engine not in selectable:
            raise ParameterError(option, text, f"a setting of a selected engine: "
                                 f"{', '.join(selectable)}")
        return engine
    if len(engines) != 1:
        example = f"{engines[0]}.{field}={raw}" if engines else f"ENGINE.{field}={raw}"
        raise ParameterError(option, text, f"ENGINE.KEY=VALUE naming one of the selected "
                             f"engines ({', '.join(selectable) or 'none'}), e.g. {option} "
                             f"{example}")
    return engines[0]


def parse_settings(texts: Iterable[str], engines: list[str], *, option: str = "--setting",
                   also: tuple[str, ...] = ()) -> list[tuple[str, str, str]]:
    """One field per text (:func:`split_field`) -> ``[(engine, key, raw value), ...]``. ENGINE
    must be one of ``engines`` or ``also`` (e.g. the analytic reference of ``compare``); a bare
    KEY belongs to the one engine of ``engines`` (an error with several). Errors are
    :class:`ParameterError` lines showing the right form."""
    selectable = list(dict.fromkeys([*engines, *also]))
    out = []
    for text in texts:
        engine, field, raw = split_field(text, option)
        out.append((_selected(engine, text, field, raw, engines, selectable, option), field,
                    raw))
    return out


@dataclass(frozen=True)
class Overrides:
    """A set of Settings overrides: ``engine`` (None: every engine it is applied to) and
    ``values`` (name, value) pairs; ``text`` True when the values are still text, typed by
    :meth:`for_engine` against the engine they are applied to."""

    engine: str | None
    values: tuple[tuple[str, Any], ...]
    text: bool = False

    def applies_to(self, engine: str) -> bool:
        return self.engine is None or self.engine == engine

    def for_engine(self, engine: str, option: str = "setting") -> dict[str, Any]:
        """The overrides as ``engine``'s Settings takes them (text typed by its fields)."""
        if not self.text:
            return dict(self.values)
        cls = _settings_class(engine)
        return {k: setting_value(cls, k, v, f"{option} {engine}.{k}") for k, v in self.values}


def parse_overrides(text: str | Mapping[str, Any] | Overrides, engines: list[str] | None = None,
                    *, option: str = "--setting") -> Overrides:
    """A set of fields of one engine (the module docstring's third and fourth forms) ->
    :class:`Overrides`. A mapping is one set for every engine (values as given). With
    ``engines`` (the command line's selection) the fields are typed and validated now, a bare
    set belongs to the one engine selected, and an ENGINE must be one of them; without, a
    bare set is for every engine and stays text until it is applied."""
    if isinstance(text, Overrides):
        return text
    if isinstance(text, Mapping):
        return Overrides(None, tuple(text.items()))
    parts = [t.strip() for t in str(text).split(",") if t.strip()]
    if not parts:
        raise ParameterError(option, text, "KEY=VALUE or ENGINE.KEY=VALUE,KEY=VALUE")
    fields = [split_field(p, option) for p in parts]
    named = {e for e, _, _ in fields if e is not None}
    if len(named) > 1:
        raise ParameterError(option, text, "fields of one engine (ENGINE.KEY=VALUE,"
                             "ENGINE.KEY=VALUE); repeat --setting for another engine")
    engine = named.pop() if named else None
    values = tuple((k, v) for _, k, v in fields)
    if engines is None:
        return Overrides(engine, values, text=True)
    engine = _selected(engine, str(text), values[0][0], values[0][1], engines, list(engines),
                       option)
    cls = _settings_class(engine)
    typed: dict[str, Any] = {}
    for k, v in values:
        if k in typed:
            raise ParameterError(f"{option} {engine}.{k}", v, "given once")
        typed[k] = setting_value(cls, k, v, f"{option} {engine}.{k}")
    cls(**typed)                     # validate now: the error names the field
    return Overrides(engine, tuple(typed.items()))
