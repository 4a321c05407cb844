"""One finding: a sentence of the report's findings with its numbers, each number with
the file and cell it was read from (a leaf: :mod:`.findings` composes them, the
drop-one-LED refits write their own, neither imports the other back)."""

from __future__ import annotations

import string
from dataclasses import dataclass

from ...formatting import format_number

__all__ = ["Value", "Finding"]


@dataclass(frozen=True)
class Value:
    """One number of a finding and where it was read from.

    Attributes
    ----------
    value : float
        The number, unrounded.
    digits : int
        Decimals shown. [-]
    sources : tuple of str
        Where it was read (see the module's *Sources*); two for a derived value.
    op : str
        ``""`` (read as is), ``"diff"``, ``"ratio"``, ``"share_removed"`` or ``"count"``.
    sign : bool
        Show a sign.
    scale : float
        Factor applied before showing (100 for a share shown in %). [-]

    Examples
    --------
    >>> Value(13.649, 1, ("paper/metrics.json:ebl:rmse_mgdl",)).text()
    '13.6'
    >>> Value(0.758, 0, ("a", "b"), op="share_removed", scale=100.0).text()
    '76'
    """

    value: float
    digits: int = 1
    sources: tuple[str, ...] = ()
    op: str = ""
    sign: bool = False
    scale: float = 1.0

    def text(self) -> str:
        """The number as shown."""
        value = float(self.value) * self.scale
        return format_number(value, self.digits, sign=self.sign, thousands=self.digits == 0)


@dataclass(frozen=True)
class Finding:
    """One sentence of the findings.

    Attributes
    ----------
    topic : str
        ``best``, ``distance``, ``physics``, ``claims``, ``presets``, ``subjects``,
        ``range`` or ``subgroups``.
    preset : str or None
        The preset it is about (None: every preset).
    template : str
        The sentence with one ``{}`` per value (plain text, no markup).
    values : tuple of Value
        The numbers, in template order.
    anchor : str
        Id of the report element (figure or table) behind the sentence.

    Examples
    --------
    >>> Finding("best", "paper", "Best: {} mg/dL.", (Value(4.0),), "fig-headline").text()
    'Best: 4.0 mg/dL.'
    """

    topic: str
    preset: str | None
    template: str
    values: tuple[Value, ...]
    anchor: str

    def parts(self) -> list[str | Value]:
        """The template's literal text and the values, in order."""
        out: list[str | Value] = []
        k = 0
        for literal, name, _, _ in string.Formatter().parse(self.template):
            if literal:
                out.append(literal)
            if name is not None:
                out.append(self.values[k])
                k += 1
        return out

    def text(self) -> str:
        """The sentence with its numbers."""
        return self.template.format(*(v.text() for v in self.values))
