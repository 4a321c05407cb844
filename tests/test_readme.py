"""The README documents what the code does."""

from __future__ import annotations

from pathlib import Path

from nirglucose.features import enhanced_beer_lambert

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_starts_with_the_two_commands():
    text = README.read_text()
    head = text[: text.index("## ")]
    assert "make run" in head and "make test" in head


def test_readme_lists_every_feature(paper_small):
    text = README.read_text()
    names = enhanced_beer_lambert(paper_small.frame.head(3)).columns
    assert len(names) == 56
    missing = [n for n in names if f"`{n}`" not in text]
    assert not missing, missing
