"""``bearings log info FILE`` and ``bearings log check FILE MISSION``: what a sensor log holds, and
whether it holds what a mission reads (docs/recorded-data.md)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from drivers.logs.source import LogContents, LogError, LogReader
from maps.store import InputError
from missions.commands.common import EXIT_INVALID, EXIT_OK, add_mission_options, load_from_args, print_input_error

if TYPE_CHECKING:
    from drivers.logs.topics import Topics

DESCRIPTION = """Sensor logs: MCAP files that 'bearings run --record' writes, ROS 2 bag folders (sqlite3 or
MCAP storage) and ROS 1 bags.

  info FILE             topics (type, messages, rate), duration, the cameras found and their models
  check FILE MISSION    does the log hold what the mission reads (odometry, its cameras, the pan-tilt
                        state, ranges)? Each camera's first frame is decoded. Exit 2 with what is missing.

--topics MAP.yaml says which topics are the odometry, the cameras, ... in a log that does not use the
names --record writes (docs/recorded-data.md, "The topic map")."""

EPILOG = """examples:
  bearings log info run.mcap
  bearings log check my_bag/ teach_route --topics my_robot_topics.yaml --set camera=front

exit codes: 0 fine, 2 a log or topic map that cannot be read, or a log that lacks what the mission reads."""


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("log", help="what a sensor log (MCAP, ROS bag) holds; check it against a mission",
                                   description=DESCRIPTION, epilog=EPILOG,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    verbs = parser.add_subparsers(dest="verb", metavar="VERB", required=True)
    info = verbs.add_parser("info", help="topics, rates, duration, cameras found")
    info.add_argument("log", metavar="FILE", type=Path, help="an MCAP file, a ROS 2 bag folder or a ROS 1 .bag")
    info.add_argument("--topics", metavar="MAP.yaml", type=Path, help="the topic map (default: --record's names)")
    info.add_argument("--json", action="store_true", help="print JSON instead of text")
    info.set_defaults(func=run_info)
    check = verbs.add_parser("check", help="does the log hold what a mission reads? (exit 2 if not)")
    check.add_argument("log", metavar="FILE", type=Path, help="an MCAP file, a ROS 2 bag folder or a ROS 1 .bag")
    check.add_argument("mission", metavar="MISSION", help="mission file, or the name of a shipped mission")
    check.add_argument("--topics", metavar="MAP.yaml", type=Path, help="the topic map (default: --record's names)")
    add_mission_options(check)
    check.set_defaults(func=run_check)


def run_info(args: argparse.Namespace) -> int:
    from drivers.logs.reader import open_log  # the log libraries load when a log command runs
    from missions.log_check import open_topics

    try:
        reader = open_log(args.log)
    except LogError as exc:
        return _failed(exc)
    try:
        topics = open_topics(reader, args.topics)
        summary = describe(reader, topics)
    except (InputError, LogError) as exc:
        return _failed(exc)
    finally:
        reader.close()
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print("\n".join(info_lines(summary)))
    return EXIT_OK


def run_check(args: argparse.Namespace) -> int:
    from drivers.logs.reader import open_log  # the log libraries load when a log command runs
    from missions.log_check import check_log, mission_needs, open_topics

    try:
        mission = load_from_args(args.mission, args)
        reader = open_log(args.log)
    except (InputError, LogError) as exc:
        return _failed(exc)
    try:
        topics = open_topics(reader, args.topics)
        findings = check_log(args.log, topics, reader.contents(), mission_needs(mission))
    except (InputError, LogError) as exc:
        return _failed(exc)
    finally:
        reader.close()
    for finding in findings:
        print(finding)
    missing = [f for f in findings if f.required and not f.ok]
    if missing:
        print(f"{args.log}: {len(missing)} input(s) of {mission.name} missing: {', '.join(f.role for f in missing)}",
              file=sys.stderr)
        return EXIT_INVALID
    print(f"OK: {args.log} holds what {mission.name} reads")
    return EXIT_OK


def describe(reader: LogReader, topics: Topics) -> dict[str, Any]:
    """What ``bearings log info`` says: the file, its topics, and the cameras found with their models."""
    from drivers.logs.reader import file_size
    from missions.log_check import Needs, check_log

    contents = reader.contents()
    needs = Needs(cameras=tuple(topics.cameras), ptu=True, ranges=True)
    findings = {f.role: f for f in check_log(reader.path, topics, contents, needs)}
    out: dict[str, Any] = {
        "file": str(reader.path), "format": contents.format, "bytes": file_size(reader.path),
        "duration_s": round(contents.duration_s, 3), "messages": contents.messages,
        "topics": [{"topic": t.name, "type": t.type, "messages": t.count, "rate_hz": _rate(contents, t.count),
                    **({"problem": t.problem} if t.problem else {})} for t in sorted(contents.topics.values(),
                                                                                    key=lambda t: t.name)],
        "cameras": {name: {"ok": findings[f"camera {name}"].ok, "found": findings[f"camera {name}"].text}
                    for name in topics.cameras},
        "odometry": {"ok": findings["odometry"].ok, "found": findings["odometry"].text},
    }
    for role in ("pan-tilt", "ranges"):
        if role in findings and findings[role].ok:
            out[role] = findings[role].text
    if contents.metadata:
        out["recorded"] = contents.metadata
    if contents.cut:
        out["cut"] = contents.cut
    return out


def info_lines(summary: dict[str, Any]) -> list[str]:
    """The text of ``bearings log info``."""
    lines = [f"{summary['file']}: {summary['format']}, {summary['duration_s']:.1f} s, {summary['messages']} messages, "
             f"{summary['bytes'] / 1e6:.1f} MB"]
    if "cut" in summary:
        lines.append(f"  {summary['cut']}")
    recorded = summary.get("recorded")
    if recorded:
        lines.append("  recorded: " + ", ".join(f"{k} {v}" for k, v in recorded.items() if k != "times"))
    lines.append("topics:")
    width = max((len(t["topic"]) for t in summary["topics"]), default=0)
    for topic in summary["topics"]:
        rate = f"{topic['rate_hz']:6.1f} Hz" if topic["rate_hz"] else " " * 9
        problem = f"  ({topic['problem']})" if "problem" in topic else ""
        lines.append(f"  {topic['topic']:{width}}  {topic['type'] or '?':34} {topic['messages']:7d}  {rate}{problem}")
    lines.append("cameras:" if summary["cameras"] else "cameras: none found (name them in a topic map: --topics)")
    for name, camera in summary["cameras"].items():
        lines.append(f"  {name}: {camera['found']}" if camera["ok"] else f"  {name}: cannot be read: {camera['found']}")
    odometry = summary["odometry"]
    lines.append(f"odometry: {odometry['found']}" if odometry["ok"] else f"odometry: MISSING: {odometry['found']}")
    for role in ("pan-tilt", "ranges"):
        if role in summary:
            lines.append(f"{role}: {summary[role]}")
    return lines


def _rate(contents: LogContents, count: int) -> float | None:
    from missions.log_check import rate

    value = rate(contents, count)
    return round(value, 2) if value else None


def _failed(exc: InputError | LogError) -> int:
    """A map or mission that does not load, or a log that does not read: its lines, exit 2."""
    if isinstance(exc, InputError):
        return print_input_error(exc)
    print(str(exc), file=sys.stderr)
    return EXIT_INVALID
