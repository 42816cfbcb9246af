"""Words for the numbers the commands, reports and figures print."""

from __future__ import annotations


def counted(n: object, noun: str) -> str:
    """``n`` and ``noun``, plural unless ``n`` is one: "1 match", "3 matches", "1 tick",
    "300 ticks" (``n`` as a CSV cell gives it too: "1", "300")."""
    if str(n) == "1":
        return f"{n} {noun}"
    return f"{n} {noun}" + ("es" if noun.endswith(("ch", "sh", "s", "x")) else "s")
