"""The colour of each contact label, shared by the planar and the spatial figures."""

from __future__ import annotations

__all__ = ["COLORS"]

COLORS = {"a": "tab:blue", "b": "tab:orange", "c": "tab:green", "d": "tab:red"}
"""Contact label -> matplotlib colour (a hand has at most four contacts)."""
