"""The sections of docs/results.md, each written by the benchmark or quality script that measures it.

A section is the text between two marker lines, ``<!-- results:NAME -->`` and ``<!-- /results:NAME -->``. Writing
one replaces what lies between its markers (or appends the pair at the end of the document when it is not there
yet) and leaves every other byte of the document as it was. Each section starts with the run that made it: the
command, the date, the git commit (with a note when the working tree had uncommitted changes) and the machine.

    python scripts/results_doc.py NAME --command CMD [--from FILE] [--markdown]   # the text of FILE (or stdin)
    python scripts/results_doc.py NAME --run [--markdown] [--ok-codes 0 1] -- CMD ARG...   # run CMD, keep its output

``--run`` is what the scripts use: it runs the command with ``FDI_RESULTS_SECTION=NAME`` in its environment (a
script that calls ``--run`` on itself sees the variable and does its work instead), passes its standard output
through and keeps it (standard error only passes), and writes the section when the command exits with one of
``--ok-codes`` (default 0). ``FDI_RESULTS_DOC`` names another document; set to an empty string, nothing is written
(a trial run that must not touch docs/results.md).
Only the standard library: the scripts call it before or without the project's venv.
"""

from __future__ import annotations

import argparse
import datetime
import io
import os
import platform
import re
import shlex
import subprocess
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TextIO

REPO = Path(__file__).resolve().parents[1]
DOC = REPO / "docs" / "results.md"
NAME = re.compile(r"[a-z][a-z0-9_]*")
MARKER = re.compile(r"^<!-- (/?)results:([^ ]*) -->[ \t]*$", re.MULTILINE)
ENV_SECTION = "FDI_RESULTS_SECTION"
ENV_DOC = "FDI_RESULTS_DOC"


class MarkerError(ValueError):
    """The document's markers are not well-formed pairs: nothing is written."""


def begin_marker(name: str) -> str:
    return f"<!-- results:{name} -->"


def end_marker(name: str) -> str:
    return f"<!-- /results:{name} -->"


def check_markers(text: str) -> list[tuple[str, int, int]]:
    """The sections of `text` as (name, start of the begin line, start of the end line), in order. Raises
    `MarkerError` for a marker with a bad name, an end without its begin, a begin without its end, a section
    opened twice or opened inside another one."""
    sections: list[tuple[str, int, int]] = []
    seen: set[str] = set()
    open_name: str | None = None
    open_at = 0
    for m in MARKER.finditer(text):
        closing, name = m.group(1) == "/", m.group(2)
        line = text.count("\n", 0, m.start()) + 1
        if not NAME.fullmatch(name):
            raise MarkerError(f"line {line}: bad section name {name!r} (lower case letters, digits, _)")
        if not closing:
            if open_name is not None:
                raise MarkerError(f"line {line}: section {name!r} opened inside section {open_name!r}")
            if name in seen:
                raise MarkerError(f"line {line}: section {name!r} appears twice")
            open_name, open_at = name, m.start()
        else:
            if open_name != name:
                raise MarkerError(f"line {line}: end of section {name!r} without its begin")
            sections.append((name, open_at, m.start()))
            seen.add(name)
            open_name = None
    if open_name is not None:
        raise MarkerError(f"section {open_name!r} is never closed ({end_marker(open_name)})")
    return sections


def replace_section(text: str, name: str, content: str) -> str:
    """`text` with section `name` holding `content` (appended at the end when the section is new)."""
    if not NAME.fullmatch(name):
        raise MarkerError(f"bad section name {name!r} (lower case letters, digits, _)")
    body = content.strip("\n") + "\n"
    for sec, begin, end in check_markers(text):
        if sec == name:
            start = text.index("\n", begin) + 1
            return text[:start] + body + text[end:]
    sep = "" if not text or text.endswith("\n\n") else ("\n" if text.endswith("\n") else "\n\n")
    return f"{text}{sep}{begin_marker(name)}\n{body}{end_marker(name)}\n"


def section_text(text: str, name: str) -> str | None:
    """What section `name` of `text` holds (without its markers), or None."""
    for sec, begin, end in check_markers(text):
        if sec == name:
            return text[text.index("\n", begin) + 1:end]
    return None


def _git(*args: str) -> str:
    try:
        out = subprocess.run(["git", *args], cwd=REPO, capture_output=True, text=True, timeout=30, check=True)
    except (OSError, subprocess.SubprocessError):
        return ""
    return out.stdout.strip()


def machine() -> str:
    """The CPU model, its cores and the system, e.g. ``AMD EPYC, 2 cores, Linux 6.1 x86_64``."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text(encoding="utf-8").splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count() or '?'} cores, {platform.system()} {platform.release()} {platform.machine()}"


def run_header(command: str, when: datetime.datetime | None = None, commit: str | None = None,
               dirty: bool | None = None, host: str | None = None) -> str:
    """The line that says which run made a section; the arguments left out are taken from this run."""
    when = when or datetime.datetime.now().astimezone()
    if commit is None:
        commit = _git("rev-parse", "--short=10", "HEAD") or "unknown"
    if dirty is None:
        # the results document itself does not count: earlier sections written in this working tree change it
        dirty = bool(_git("status", "--porcelain", "--untracked-files=no", "--", ".",
                          f":(exclude){DOC.relative_to(REPO).as_posix()}"))
    state = " with uncommitted changes in the working tree" if dirty else ""
    return (f"*Generated by `{command}` on {when:%Y-%m-%d %H:%M %Z}, commit {commit}{state}, "
            f"on {host or machine()}.*")


def section_content(output: str, command: str, markdown: bool = False, when: datetime.datetime | None = None,
                    commit: str | None = None, dirty: bool | None = None, host: str | None = None) -> str:
    """The run's header and its output: Markdown as it is, plain text in a code block."""
    out = output.strip("\n")
    if not markdown:
        fence = "```"
        while fence in out:
            fence += "`"
        out = f"{fence}text\n{out}\n{fence}"
    return f"{run_header(command, when, commit, dirty, host)}\n\n{out}\n"


def write_section(name: str, output: str, command: str, doc: Path | None = None, markdown: bool = False) -> Path:
    """Write section `name` of `doc` (default docs/results.md, or $FDI_RESULTS_DOC) from a run's output."""
    path = doc if doc is not None else Path(os.environ.get(ENV_DOC) or DOC)
    text = path.read_text(encoding="utf-8") if path.exists() else "# Results\n"
    new = replace_section(text, name, section_content(output, command, markdown))
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(new, encoding="utf-8")
    tmp.replace(path)
    return path


def writing_enabled() -> bool:
    return os.environ.get(ENV_DOC, None) != ""


class Tee(io.TextIOBase):
    """A text stream that writes through to `stream` and keeps a copy."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream
        self.copy = io.StringIO()

    def write(self, s: str) -> int:
        self.copy.write(s)
        return self.stream.write(s)

    def flush(self) -> None:
        self.stream.flush()

    def fileno(self) -> int:
        return self.stream.fileno()

    def isatty(self) -> bool:
        return self.stream.isatty()


def tee_main(name: str, main: Callable[[], int], command: str, ok_codes: Sequence[int] = (0,)) -> int:
    """Run a Python benchmark's `main` with its standard output kept, then write section `name` from it when
    `main` returned one of `ok_codes`; returns `main`'s code."""
    tee = Tee(sys.stdout)
    saved, sys.stdout = sys.stdout, tee
    try:
        rc = main()
    finally:
        sys.stdout = saved
    if rc in ok_codes and writing_enabled():
        path = write_section(name, tee.copy.getvalue(), command)
        print(f"wrote section {name} of {path}", file=sys.stderr)
    return rc


def run_command(name: str, argv: Sequence[str], ok_codes: Sequence[int] = (0,), markdown: bool = False,
                display: str | None = None) -> int:
    """Run `argv` with its standard output passed through and kept (its standard error, progress bars and
    warnings, only passed through); write section `name` from that output when the command exits with one of
    `ok_codes`."""
    env = dict(os.environ, **{ENV_SECTION: name})
    proc = subprocess.Popen(list(argv), env=env, stdout=subprocess.PIPE, text=True, bufsize=1)
    kept: list[str] = []
    assert proc.stdout is not None
    try:
        for line in proc.stdout:
            sys.stdout.write(line)
            sys.stdout.flush()
            kept.append(line)
        rc = proc.wait()
    except KeyboardInterrupt:
        proc.wait()
        return 130
    command = display or shlex.join(argv)
    if rc in ok_codes and writing_enabled():
        path = write_section(name, "".join(kept), command, markdown=markdown)
        print(f"wrote section {name} of {path}", file=sys.stderr)
    return rc


def run_script(name: str, script: str, argv: Sequence[str], ok_codes: Sequence[int] = (0,),
               markdown: bool = False) -> int | None:
    """What a Python benchmark calls first under ``__main__``: unless it already runs under a section (or is asked
    for its help), run `script` again with `argv` under `run_command`, so that its whole output, a child
    process's included, becomes section `name`; returns that run's exit code, or None when the caller is that run
    and does its work."""
    if os.environ.get(ENV_SECTION) or "-h" in argv or "--help" in argv:
        return None
    path = Path(script).resolve()
    shown = path.relative_to(REPO) if path.is_relative_to(REPO) else path
    return run_command(name, [sys.executable, str(path), *argv], ok_codes, markdown,
                       display=shlex.join(["python", str(shown), *argv]))


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("name", help="the section's name (lower case letters, digits, _)")
    ap.add_argument("--command", help="the command that made the output (for the section's header)")
    ap.add_argument("--from", dest="source", type=Path, help="the output to write (default: standard input)")
    ap.add_argument("--markdown", action="store_true", help="the output is Markdown: written as it is, not in a "
                    "code block")
    ap.add_argument("--run", action="store_true", help="run the command after -- and write its output")
    ap.add_argument("--ok-codes", type=int, nargs="+", default=[0], help="with --run: exit codes of a run whose "
                    "output is written (default 0)")
    ap.add_argument("--display", help="with --run: the command as the header shows it (default: the one run)")
    argv = list(sys.argv[1:] if argv is None else argv)
    cut = argv.index("--") if "--" in argv else len(argv)
    args, rest = ap.parse_args(argv[:cut]), argv[cut + 1:]
    try:
        if args.run:
            if not rest:
                ap.error("--run needs a command after --")
            return run_command(args.name, rest, args.ok_codes, args.markdown, args.display)
        if rest or not args.command:
            ap.error("give --command CMD (and --from FILE or standard input), or --run -- CMD ...")
        text = args.source.read_text(encoding="utf-8") if args.source else sys.stdin.read()
        path = write_section(args.name, text, args.command, markdown=args.markdown)
    except (MarkerError, OSError) as exc:
        print(f"results_doc: error: {exc}", file=sys.stderr)
        return 1
    print(f"wrote section {args.name} of {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
