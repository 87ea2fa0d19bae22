"""Summary of what the test run skipped and why, from the JUnit XML reports of CTest and pytest.

Usage: python scripts/skip_summary.py REPORT.xml [REPORT.xml ...]   (called at the end of scripts/test.sh)
Prints one line per report (tests, failures, skips) and every skipped test with its reason; a report that is
missing is named. A skip is never silent: the README lists the skips to expect on a machine without root.
"""

from __future__ import annotations

import sys
import xml.etree.ElementTree as ET
from pathlib import Path

CMOCKA_SKIP = "[  SKIPPED ]"


def _skips(case: ET.Element) -> list[str]:
    """The reasons a test case was skipped (empty when it ran): pytest's and CTest's <skipped> element, and
    the cmocka skip() lines in a CTest test's output."""
    out = []
    for sk in case.findall("skipped"):
        out.append((sk.get("message") or sk.text or "skipped").strip())
    text = "".join(e.text or "" for e in case.findall("system-out"))
    out += [line.strip() for line in text.splitlines() if CMOCKA_SKIP in line]
    return out


def main(argv: list[str]) -> int:
    total_skips = 0
    lines: list[str] = []
    for arg in argv:
        path = Path(arg)
        if not path.is_file():
            lines.append(f"  {arg}: no report (that part did not run)")
            continue
        cases = ET.parse(path).getroot().iter("testcase")
        n = failures = skipped = 0
        details = []
        for case in cases:
            n += 1
            failures += bool(case.findall("failure") or case.findall("error"))
            why = _skips(case)
            if why:
                skipped += 1
                name = f"{case.get('classname', '')}::{case.get('name', '')}".strip(":")
                details += [f"    SKIPPED {name}: {w}" for w in why]
        total_skips += skipped
        lines.append(f"  {arg}: {n} tests, {failures} failed, {skipped} skipped")
        lines += details
    print(f"== skipped tests: {total_skips}")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
