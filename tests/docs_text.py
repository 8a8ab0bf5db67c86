"""What the documentation names: ``bearings`` command lines and repository paths, read from Markdown.

Used by ``tests/missions/test_docs.py``: every command line in README.md and docs/ is checked
against the CLI's parser, every path they cite must exist inside the repository, and the README's
examples are run. A command line is *complete* when it has no placeholder (``MISSION``,
``F.json``, ``[...]``, ``a|b`` alternatives, ``my_...`` names): those are parsed as they are;
the others are checked for their command, sub-command, option names and choices.
"""

from __future__ import annotations

import re
import shlex
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGES = (ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")))
TOP_LEVEL = frozenset(p.name for p in ROOT.iterdir() if not p.name.startswith(".") or p.name == ".ci") - {
    ".venv", "bearings.egg-info", "out", "results"}
SHELL_BLOCKS = ("", "bash", "sh", "shell", "console")

FENCE = re.compile(r"^```(\w*)\n(.*?)^```", re.S | re.M)
INLINE = re.compile(r"(?<!`)`([^`\n]+)`(?!`)")
LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")
COMMAND = re.compile(r"(?:^|&&|;)\s*(?:\$\s*)?(?:[\w./-]*/)?bearings(?:\s+(.*?))?\s*(?=&&|;|$)")
PLACEHOLDER = re.compile(r"\b[A-Z][A-Z0-9_]+\b|\.\.\.|[\[\]<>]|\bmy[_-]|path/to/|\w\|\w")
CAPS_MD = re.compile(r"\b[A-Z][A-Z_]+\.md\b")
ISSUE = re.compile(r"\bissue\s+#?\d+", re.I)


@dataclass(frozen=True)
class Mention:
    """A command line or a path as a page writes it, and where."""

    page: Path
    line: int
    text: str
    in_block: bool = False

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def _without_blocks(text: str) -> str:
    """The page with its fenced blocks blanked (line numbers kept)."""
    return FENCE.sub(lambda m: "\n" * m.group(0).count("\n"), text)


def _lines(page: Path) -> tuple[str, list[tuple[int, str, bool]]]:
    text = page.read_text(encoding="utf-8")
    blocks = []
    for match in FENCE.finditer(text):
        if match.group(1) in SHELL_BLOCKS:
            first = text.count("\n", 0, match.start(2)) + 1
            joined = match.group(2).replace("\\\n", " ")
            for offset, line in enumerate(joined.splitlines()):
                blocks.append((first + offset, line, True))
    return text, blocks


def commands(page: Path) -> Iterator[Mention]:
    """Every ``bearings ...`` command line of a page: in shell blocks, and in inline code spans."""
    text, blocks = _lines(page)
    for number, line, _ in blocks:
        code = line.split(" #")[0]
        for match in COMMAND.finditer(code):
            yield Mention(page, number, (match.group(1) or "").strip(), True)
    plain = _without_blocks(text)
    for number, line in enumerate(plain.splitlines(), 1):
        for span in INLINE.findall(line):
            if span.startswith("bearings ") or span == "bearings":
                yield Mention(page, number, span[len("bearings"):].strip())


def example_block(page: Path, heading: str) -> list[Mention]:
    """The command lines of the first shell block under ``heading`` (complete commands, in order)."""
    text = page.read_text(encoding="utf-8")
    section = text.index(heading)
    match = FENCE.search(text, section)
    assert match is not None
    return [m for m in commands(page) if m.in_block and text.count("\n", 0, match.start(2)) < m.line
            <= text.count("\n", 0, match.end())]


def is_complete(command: str) -> bool:
    return not PLACEHOLDER.search(command)


def tokens(command: str) -> list[str]:
    return shlex.split(command, comments=True)


def cited_paths(page: Path) -> Iterator[Mention]:
    """Paths a page cites: link targets, and code spans or command words that name a repository path."""
    text = page.read_text(encoding="utf-8")
    for number, line in enumerate(text.splitlines(), 1):
        for target in LINK.findall(line):
            if not re.match(r"^(?:https?:|mailto:|#)", target):
                yield Mention(page, number, target.split("#")[0])
        words = [w for span in INLINE.findall(line) for w in span.split()]
        words += line.split() if line.startswith(("bearings", ".venv/bin", "    ")) else []
        for word in words:
            word = word.strip("`'\",;:()")
            if word.startswith("../") or word.split("/")[0] in TOP_LEVEL and "/" in word:
                yield Mention(page, number, word.split("::")[0])


def foreign_citations(page: Path) -> Iterator[Mention]:
    """Citations of what a clone does not hold: upper-case design files and issue numbers."""
    for number, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1):
        for found in (*CAPS_MD.findall(line), *ISSUE.findall(line)):
            yield Mention(page, number, found)
