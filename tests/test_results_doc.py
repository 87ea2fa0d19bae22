"""scripts/results_doc.py, the writer of docs/results.md's sections: writing a section replaces its own text, keeps
every other byte, appends a new section, and refuses a document whose markers are not well-formed pairs."""

from __future__ import annotations

import datetime
import importlib.util
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import pytest

REPO = Path(__file__).resolve().parents[1]


def _load() -> ModuleType:
    spec = importlib.util.spec_from_file_location("results_doc", REPO / "scripts" / "results_doc.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["results_doc"] = module
    spec.loader.exec_module(module)
    return module


rd = _load()

DOC = """# Results

Hand-written text before.

<!-- results:alpha -->
old alpha
<!-- /results:alpha -->

Between the sections, by hand.

<!-- results:beta -->
old beta
two lines
<!-- /results:beta -->
Trailing text.
"""


def test_replacing_a_section_keeps_the_others() -> None:
    new = rd.replace_section(DOC, "alpha", "new alpha\nmore")
    assert rd.section_text(new, "alpha") == "new alpha\nmore\n"
    assert rd.section_text(new, "beta") == rd.section_text(DOC, "beta")
    # every byte outside alpha's markers is the same
    head, tail = DOC.split("old alpha\n")
    assert new == head + "new alpha\nmore\n" + tail


def test_replacing_the_last_section_keeps_what_follows() -> None:
    new = rd.replace_section(DOC, "beta", "b")
    assert new.endswith("<!-- /results:beta -->\nTrailing text.\n")
    assert rd.section_text(new, "beta") == "b\n" and "old alpha" in new


def test_writing_twice_gives_the_same_document() -> None:
    once = rd.replace_section(DOC, "beta", "x\n\n")
    assert rd.replace_section(once, "beta", "x") == once


def test_a_new_section_is_appended() -> None:
    new = rd.replace_section(DOC, "gamma", "g")
    assert new.startswith(DOC)
    assert [s[0] for s in rd.check_markers(new)] == ["alpha", "beta", "gamma"]
    assert rd.section_text(new, "gamma") == "g\n"


@pytest.mark.parametrize("text, message", [
    ("<!-- results:a -->\nx\n", "never closed"),
    ("x\n<!-- /results:a -->\n", "without its begin"),
    ("<!-- results:a -->\n<!-- results:b -->\n<!-- /results:b -->\n<!-- /results:a -->\n", "inside"),
    ("<!-- results:a -->\n<!-- /results:b -->\n", "without its begin"),
    ("<!-- results:a -->\n<!-- /results:a -->\n<!-- results:a -->\n<!-- /results:a -->\n", "twice"),
    ("<!-- results:Bad-Name -->\n<!-- /results:Bad-Name -->\n", "bad section name"),
])
def test_a_malformed_marker_pair_is_refused(text: str, message: str) -> None:
    with pytest.raises(rd.MarkerError, match=message):
        rd.replace_section(text, "a", "new")


def test_a_malformed_pair_elsewhere_is_refused_too(tmp_path: Path) -> None:
    """Writing one section never goes ahead in a document whose other markers are broken, and leaves it as it was."""
    doc = tmp_path / "results.md"
    broken = DOC.replace("<!-- /results:beta -->\n", "")
    doc.write_text(broken, encoding="utf-8")
    with pytest.raises(rd.MarkerError, match="beta"):
        rd.write_section("alpha", "new", "cmd", doc=doc)
    assert doc.read_text(encoding="utf-8") == broken


def test_a_bad_name_is_refused() -> None:
    with pytest.raises(rd.MarkerError):
        rd.replace_section(DOC, "no spaces", "x")


def test_the_header_names_the_run() -> None:
    when = datetime.datetime(2026, 12, 7, 3, 4, tzinfo=datetime.UTC)
    text = rd.section_content("line 1\nline 2\n", "bash scripts/x.sh 3", when=when, commit="abc1234", dirty=True,
                              host="CPU X, 2 cores")
    first, rest = text.split("\n", 1)
    for part in ("`bash scripts/x.sh 3`", "2026-12-07 03:04", "abc1234", "uncommitted", "CPU X, 2 cores"):
        assert part in first, part
    assert "```text\nline 1\nline 2\n```" in rest
    clean = rd.section_content("| a |\n", "c", markdown=True, when=when, commit="abc1234", dirty=False, host="h")
    assert "uncommitted" not in clean and clean.endswith("\n\n| a |\n") and "```" not in clean


def test_a_fence_inside_the_output_is_kept_whole() -> None:
    text = rd.section_content("a\n```\nb", "c", commit="x", dirty=False, host="h")
    assert "````text\na\n```\nb\n````" in text


def test_run_writes_its_section_only_on_success(tmp_path: Path) -> None:
    doc = tmp_path / "results.md"
    doc.write_text(DOC, encoding="utf-8")
    env_cmd = [sys.executable, str(REPO / "scripts" / "results_doc.py")]
    script = "import os; print('section', os.environ['FDI_RESULTS_SECTION']); raise SystemExit({})"
    env = {"FDI_RESULTS_DOC": str(doc), "PATH": "/usr/bin:/bin"}
    ok = subprocess.run([*env_cmd, "alpha", "--run", "--", sys.executable, "-c", script.format(0)], env=env,
                        capture_output=True, text=True, timeout=60)
    assert ok.returncode == 0 and ok.stdout == "section alpha\n", ok.stderr
    alpha = rd.section_text(doc.read_text(encoding="utf-8"), "alpha")
    assert alpha is not None and "```text\nsection alpha\n```" in alpha and "-c" in alpha.splitlines()[0]
    assert rd.section_text(doc.read_text(encoding="utf-8"), "beta") == "old beta\ntwo lines\n"
    before = doc.read_text(encoding="utf-8")
    failed = subprocess.run([*env_cmd, "beta", "--run", "--", sys.executable, "-c", script.format(3)], env=env,
                            capture_output=True, text=True, timeout=60)
    assert failed.returncode == 3 and doc.read_text(encoding="utf-8") == before
    dry = subprocess.run([*env_cmd, "beta", "--run", "--", sys.executable, "-c", script.format(0)],
                         env={**env, "FDI_RESULTS_DOC": ""}, capture_output=True, text=True, timeout=60)
    assert dry.returncode == 0 and doc.read_text(encoding="utf-8") == before


def test_the_committed_document_is_well_formed() -> None:
    """docs/results.md: every section a well-formed pair, each headed with the run that made it or carried over."""
    text = (REPO / "docs" / "results.md").read_text(encoding="utf-8")
    sections = rd.check_markers(text)
    names = [name for name, _, _ in sections]
    for expected in ("bench_mso", "bench_fw", "quality_romo", "quality_kin", "fleet_quality"):
        assert expected in names, expected
    for name in names:
        body = rd.section_text(text, name)
        assert body is not None
        first = body.strip().splitlines()[0] if body.strip() else ""
        assert first.startswith(("*Generated by `", "*Carried over from")), f"{name}: {first!r}"


def test_a_python_benchmark_writes_its_section_with_its_child_processes_output(tmp_path: Path) -> None:
    """run_script, what a Python benchmark calls under __main__: the script runs again under the section, and what
    its own child process prints is kept too; inside that run, and for --help, it returns None (do the work)."""
    doc = tmp_path / "results.md"
    doc.write_text(DOC, encoding="utf-8")
    bench = tmp_path / "bench_x.py"
    bench.write_text(
        "import subprocess, sys\n"
        f"sys.path.insert(0, {str(REPO / 'scripts')!r})\n"
        "import results_doc\n"
        "rerun = results_doc.run_script('alpha', __file__, sys.argv[1:])\n"
        "if rerun is not None:\n"
        "    raise SystemExit(rerun)\n"
        "print('parent', sys.argv[1:], flush=True)\n"
        "subprocess.run([sys.executable, '-c', 'print(\"child line\")'], check=True)\n", encoding="utf-8")
    env = {"FDI_RESULTS_DOC": str(doc), "PATH": "/usr/bin:/bin"}
    proc = subprocess.run([sys.executable, str(bench), "--n", "3"], env=env, capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == "parent ['--n', '3']\nchild line\n"
    alpha = rd.section_text(doc.read_text(encoding="utf-8"), "alpha")
    assert alpha is not None and "parent ['--n', '3']\nchild line\n" in alpha
    assert "bench_x.py --n 3" in alpha.splitlines()[0]
    before = doc.read_text(encoding="utf-8")
    helped = subprocess.run([sys.executable, str(bench), "--help"], env=env, capture_output=True, text=True,
                            timeout=60)
    assert helped.returncode == 0 and doc.read_text(encoding="utf-8") == before
