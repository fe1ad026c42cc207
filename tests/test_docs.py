"""The docs stay true to the code: every ``LaneParams`` field with its default and every
registered method appear in docs/api.md; the README opens with the two commands of a fresh
machine; every repository path and link the README and docs/*.md name exists."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

from rld.api import METHODS
from rld.types import LaneParams

ROOT = Path(__file__).resolve().parents[1]


def _default_text(value) -> str:
    return f"{value:.6g}" if isinstance(value, float) else str(value)


def test_api_reference_lists_every_param_with_its_default():
    text = (ROOT / "docs" / "api.md").read_text()
    rows = dict(re.findall(r"^\| `(\w+)` \| ([^|]+) \|", text, flags=re.M))
    for f in dataclasses.fields(LaneParams):
        assert f.name in rows, f"docs/api.md does not list LaneParams.{f.name}"
        assert rows[f.name].strip() == _default_text(f.default), (
            f"docs/api.md gives LaneParams.{f.name} = {rows[f.name].strip()}, "
            f"the code {_default_text(f.default)}")


def test_api_reference_names_every_method():
    text = (ROOT / "docs" / "api.md").read_text()
    for name in METHODS:
        assert f"`{name}`" in text, f"docs/api.md does not name method {name!r}"


def test_readme_opens_with_the_two_commands():
    lines = (ROOT / "README.md").read_text().splitlines()
    block = lines[lines.index("```bash") + 1: lines.index("```bash") + 3]
    assert block[0].startswith("pip install . && rld demo")
    assert block[1].startswith("pip install -e '.[dev]' && pytest")


#: A repository path as the docs write it: a top-level folder of the checkout, then a file or
#: folder name (``docs/huang.md``, ``rld/tracker.py``, ``models/clc_ranker.npz``).
_REPO_PATH = re.compile(
    r"(?<![\w./-])((?:docs|rld|clc|tests|notebooks|benchmarks|models)/[\w./-]*\w)")
#: The target of a Markdown link or image, ``[text](target)``.
_LINK = re.compile(r"\]\(([^)\s#]+)[^)]*\)")


def test_paths_named_in_the_docs_exist():
    missing = []
    for page in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        text = page.read_text()
        named = [ROOT / p for p in _REPO_PATH.findall(text)]  # from the repository root
        named += [page.parent / t for t in _LINK.findall(text)  # from the page
                  if not re.match(r"[a-z]+:", t)]
        missing += [f"{page.relative_to(ROOT)}: {p.relative_to(ROOT)}" for p in named
                    if not p.exists()]
    assert not missing, "the docs name files that do not exist:\n" + "\n".join(missing)
