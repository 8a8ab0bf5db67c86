"""Figures and drawings: what a node reports, gathered into report sections."""

from __future__ import annotations

from collections.abc import Iterator

from behaviours.telemetry import Figure, Sections, report_sections, section


class _Counter:
    def __init__(self, count: int) -> None:
        self.count = count

    def figures(self) -> Iterator[Figure]:
        yield Figure("ltmap", "recoveries", self.count)
        yield Figure("roadmap", "search.scans", 2 * self.count)


def test_dotted_names_nest_and_sections_merge_across_nodes():
    gathered = Sections()
    gathered.add([Figure("roadmap", "search.scans", 4), Figure("roadmap", "search.unreachable", 1)])
    gathered.add(section("roadmap", {"edges": 3}))
    assert gathered.sections == {"roadmap": {"search": {"scans": 4, "unreachable": 1}, "edges": 3}}


def test_report_sections_of_nodes_that_report_and_nodes_that_do_not():
    assert report_sections(_Counter(3), object()) == {"ltmap": {"recoveries": 3}, "roadmap": {"search": {"scans": 6}}}
