"""THE parser of a value given as text: an engine setting (``--setting ENGINE.KEY=VALUE``,
:mod:`rockbench.engines.setting_text`) and a scene override (``--set KEY=VALUE``,
:func:`rockbench.scene.scene.apply_overrides`) take their text through :func:`parse_value`,
typed by what the field expects, never guessed from the text.
"""

from __future__ import annotations

from typing import Any

__all__ = ["parse_value", "TRUE", "FALSE", "NONE"]

#: Spellings of a boolean (any case).
TRUE = ("true", "yes", "1", "on")
FALSE = ("false", "no", "0", "off")
#: Spellings of "no value" (any case).
NONE = ("none", "null")


def parse_value(raw: str, like: Any, *, nullable: bool = False, words: tuple[str, ...] = ()
                ) -> Any:
    """``raw`` as a value of the type of ``like`` (a field's default): a bool (:data:`TRUE`,
    :data:`FALSE`), an int, a float or the text itself; for ``like`` None (a field without a
    typed default) :data:`NONE` is None, a number is a float, anything else the text.

    ``nullable``: :data:`NONE` and the empty text are None whatever ``like`` is; ``words``:
    these spellings (lower case) are returned as they are. ValueError when the text is not a
    value of that type."""
    low = raw.strip().lower()
    if nullable and (low in NONE or not low):
        return None
    if low in words:
        return low
    if isinstance(like, bool):
        if low in TRUE:
            return True
        if low in FALSE:
            return False
        raise ValueError(f"{raw!r} is not a boolean")
    if isinstance(like, int):
        return int(raw)
    if isinstance(like, float):
        return float(raw)
    if isinstance(like, str):
        return raw
    if low in NONE:
        return None
    try:
        return float(raw)
    except ValueError:
        return raw
