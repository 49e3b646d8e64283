"""The reference pages are complete and the figures they quote hold.

* docs/architecture.md names every module under ``ftkin/`` by path;
* docs/benchmarks.md names every script in ``benchmarks/``;
* a figure quoted from a benchmark sits in a region
  ``<!-- results: benchmarks/results/NAME.txt -->`` … ``<!-- /results -->``
  (docs/benchmarks.md, "Quoting a benchmark"): every number in the region is
  in that recorded output, and the region cites the run's date;
* every image in the docs is made by ``scripts/docs_images.py`` with the
  caption the page gives it;
* METHOD.md is cited only through the method page that holds it.
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
REGION = re.compile(r"<!-- results: (?P<file>\S+) -->(?P<body>.*?)<!-- /results -->", re.DOTALL)
NUMBER = re.compile(r"\d+(?:\.\d+)?(?:e[-+]?\d+)?")
IMAGE = re.compile(r"!\[(?P<alt>[^\]]*)\]\((?:docs/)?images/(?P<name>[^)]+)\)")
MYST_IMAGE = re.compile(r"```\{image\} images/(?P<name>\S+)\n:alt: (?P<alt>[^\n]*)")


def test_architecture_names_every_module():
    text = (ROOT / "docs" / "architecture.md").read_text()
    modules = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "ftkin").rglob("*.py"))
    missing = [module for module in modules if f"`{module}`" not in text]
    assert not missing, f"docs/architecture.md does not name: {', '.join(missing)}"


def test_benchmarks_page_names_every_script():
    text = (ROOT / "docs" / "benchmarks.md").read_text()
    scripts = sorted(p.name for p in (ROOT / "benchmarks").glob("*.py"))
    missing = [script for script in scripts if f"`{script}`" not in text]
    assert not missing, f"docs/benchmarks.md does not list: {', '.join(missing)}"


FENCE = re.compile(r"^```.*?^```", re.DOTALL | re.MULTILINE)


def _regions():
    for page in PAGES:
        for match in REGION.finditer(FENCE.sub("", page.read_text())):
            yield pytest.param(
                page, match["file"], match["body"], id=f"{page.name}:{match['file']}"
            )


@pytest.mark.parametrize(("page", "result", "body"), list(_regions()))
def test_quoted_figures_are_in_the_recorded_output(page, result, body):
    path = ROOT / result
    assert path.is_file(), f"{page.name} quotes {result}, which is not recorded (make bench)"
    recorded = path.read_text()
    date = re.search(r"^# date: (\d{4}-\d{2}-\d{2})", recorded, re.MULTILINE)
    assert date, f"{result} has no '# date:' header line"
    assert date[1] in body, f"{page.name} quotes {result} without citing its run of {date[1]}"
    tokens = set(NUMBER.findall(recorded))
    quoted = NUMBER.findall(re.sub(r"`[^`]*\.(?:py|txt)`", "", body))
    absent = sorted(set(quoted) - tokens, key=quoted.index)
    assert not absent, f"{page.name}: figures not in {result}: {', '.join(absent)}"


def test_the_marking_convention_is_used():
    assert len(list(_regions())) >= 1
    assert "<!-- results:" in (ROOT / "docs" / "benchmarks.md").read_text()


def _images_script():
    spec = importlib.util.spec_from_file_location(
        "docs_images", ROOT / "scripts" / "docs_images.py"
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def test_images_are_made_by_the_script_with_their_captions():
    images = _images_script().IMAGES
    for page in PAGES:
        text = page.read_text()
        for match in [*IMAGE.finditer(text), *MYST_IMAGE.finditer(text)]:
            name = match["name"]
            assert name in images, (
                f"{page.name}: images/{name} is not made by scripts/docs_images.py"
            )
            assert match["alt"] == images[name].caption, (page.name, name, match["alt"])
            assert (ROOT / "docs" / "images" / name).is_file()
    for name in images:
        assert (ROOT / "docs" / "images" / name).is_file(), name


def test_method_is_cited_through_its_page():
    assert (ROOT / "docs" / "method.md").is_file()
    for page in PAGES:
        if page.name != "method.md":
            assert "METHOD.md" not in page.read_text(), f"{page.name} cites METHOD.md"


def test_documented_file_version_is_the_written_one():
    from ftkin.io.calibration_file import FORMAT_VERSION

    text = (ROOT / "docs" / "calibration.md").read_text()
    assert f'"version": {FORMAT_VERSION}`' in text


def test_paper_values_are_quoted_as_printed_beside_ftkins():
    from ftkin.sim.paper import PAPER_RESULTS, paper_calibration

    assert PAPER_RESULTS["torque_offset"][2] == 0.0255  # a constant, as printed
    ours_z = float(paper_calibration("linear").torque_offset[2])  # 0.025446 N·m
    assert abs(ours_z - 0.0254) < 5e-5  # prints as 0.0254 at the paper's four decimals
    for page in (ROOT / "README.md", ROOT / "docs" / "calibration.md"):
        rows = [line for line in page.read_text().splitlines() if line.startswith("| M0 |")]
        assert rows == [
            "| M0 | [−0.0002, −0.0605, 0.0255] N·m | [−0.0002, −0.0605, 0.0254] N·m |"
        ], page.name


# ---------------------------------------------------------------- install lines, flags, outputs
INSTALL = re.compile(r"pip install[^`\n]*")
FROM_CHECKOUT = re.compile(r"pip install -e '\.\[(?P<extras>[a-z,-]+)\]'|pip install -e \.(?=\s|$)")


def _extras() -> set[str]:
    import tomllib

    with open(ROOT / "pyproject.toml", "rb") as file:
        return set(tomllib.load(file)["project"]["optional-dependencies"])


def _install_lines():
    for page in PAGES:
        for number, line in enumerate(page.read_text().splitlines(), 1):
            for match in INSTALL.finditer(line):
                yield pytest.param(match.group(), id=f"{page.name}:{number}")


@pytest.mark.parametrize("line", list(_install_lines()))
def test_every_install_line_installs_from_the_checkout_an_extra_it_declares(line):
    """ftkin is not on PyPI: ``pip install 'ftkin[ur]'`` fails. Every install line installs the
    checkout (``pip install -e '.[ur]'``) with extras that pyproject.toml declares."""
    match = FROM_CHECKOUT.match(line)
    assert match, f"{line!r}: install ftkin from its checkout: pip install -e '.[EXTRA]'"
    unknown = set((match["extras"] or "").split(",")) - _extras() - {""}
    assert not unknown, f"{line!r}: pyproject.toml declares no extra {', '.join(sorted(unknown))}"


def test_the_install_advice_of_a_missing_dependency_names_this_checkout_and_a_declared_extra():
    from ftkin.exceptions import MissingDependency

    used = set()
    for path in (ROOT / "ftkin").rglob("*.py"):
        used.update(re.findall(r'MissingDependency\(\s*[^,]+,\s*"([a-z-]+)"', path.read_text()))
    assert used and used <= _extras(), sorted(used - _extras())
    message = str(MissingDependency("ur_rtde", "ur", "reading a UR arm"))
    checkout = re.search(r"pip install -e '(?P<path>[^\[']+)\[ur\]'", message)
    assert checkout and (Path(checkout["path"]) / "pyproject.toml").is_file(), message


@pytest.mark.skipif(
    os.environ.get("FTKIN_DOCS_SLOW", "") in ("", "0"), reason="slow: pip builds the checkout"
)
def test_an_install_line_runs_from_the_checkout():
    """``pip install -e '.[ur]'``, dry run without dependencies, in the checkout: pip builds
    ftkin's metadata and finds the extra (it only warns about an extra it does not know)."""
    done = subprocess.run(
        [sys.executable, "-m", "pip", "install", "--dry-run", "--no-deps", "-e", ".[ur]"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    assert "does not provide the extra" not in done.stderr + done.stdout


COMMAND = re.compile(r"(?:^\s*(?:[A-Z_]+=\S*\s+)*|`|\$ )(?P<command>ftkin [^`\n]*)", re.MULTILINE)
FLAG = re.compile(r"(?<![\w-])--[a-z][a-z0-9-]*")


def _parsers() -> dict[str, set[str]]:
    """The option strings of every ftkin command, by its words (``"robot calibrate"``)."""
    import argparse

    from ftkin.cli import build_parser

    found: dict[str, set[str]] = {}

    def walk(parser, words):
        found[" ".join(words)] = {o for action in parser._actions for o in action.option_strings}
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, child in action.choices.items():
                    walk(child, [*words, name])

    walk(build_parser(), [])
    return found


def test_every_flag_the_docs_give_a_command_is_one_it_takes():
    """Each ``ftkin COMMAND ... --flag`` in README and docs (code blocks and inline code): the
    command exists and takes the flag (no abbreviations). A flag shown alone must be taken by
    some ftkin command, or be one of the other tools' the docs name."""
    parsers = _parsers()
    every = set().union(*parsers.values())
    others = {"--dry-run", "--no-deps", "--durations", "--help", "--version"}  # pip, pytest
    for script in (ROOT / "benchmarks").glob("*.py"):  # the benchmarks' own flags
        others.update(re.findall(r'add_argument\(\s*"(--[a-z][a-z0-9-]*)"', script.read_text()))
    wrong = []
    for page in PAGES:
        text = page.read_text()
        for match in COMMAND.finditer(text):
            command = re.split(r"\s(?:\||&&|;|#)\s|\\\|", match["command"])[0]
            words = command.split()[1:]
            path = []
            while words and " ".join([*path, words[0]]) in parsers:
                path.append(words.pop(0))
            flags = parsers[" ".join(path)]
            for flag in FLAG.findall(" ".join(words)):
                if flag not in flags:
                    wrong.append(f"{page.name}: `ftkin {' '.join(path)}` takes no {flag}")
        for flag in FLAG.findall(" ".join(re.findall(r"`(--[^`]*)`", text))):
            if flag not in every and flag not in others:
                wrong.append(f"{page.name}: no ftkin command takes {flag}")
    assert not wrong, "\n".join(sorted(set(wrong)))


def _docs_conftest():
    spec = importlib.util.spec_from_file_location("ftkin_docs_conftest", ROOT / "conftest.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize(
    ("expected", "actual", "same"),
    [
        (
            "wrote samples.csv: 12 poses × 50 readings",
            "wrote samples.csv: 12 poses × 50 readings",
            1,
        ),
        (
            "wrote samples.csv: 12 poses × 10 readings",
            "wrote samples.csv: 12 poses × 50 readings",
            0,
        ),
        ("from 4250 sampled", "from 4251 sampled", 0),  # an integer is exact
        ("tool 0.3217 kg", "tool 0.3218 kg", 1),  # a decimal: one unit of its last digit
        ("tool 0.3217 kg", "tool 0.3216 kg", 1),
        ("tool 0.3217 kg", "tool 0.3219 kg", 0),  # two units: stale
        ("tool 0.3217 kg", "tool 0.32171 kg", 1),
        ("G = 3.15", "G = 3.159", 1),
        ("G = 3.15", "G = 3.1601", 0),
        ("F0 [-0.8613, +1.1015]", "F0 [-0.8613, 1.1015]", 1),  # a sign is a number's
        ("F0 [-0.8613, +1.1015]", "F0 [+0.8613, +1.1015]", 0),
        ("a  b   c", "a b c", 1),  # spacing is free
        ("median |F'| ...)", "median |F'| 0.0356 N)", 1),  # ... stands for any text
        ("took ... s at load 7", "took 4.1 s at load 7", 1),
        ("took ... s at load 7", "took 4.1 s at load 8", 0),
        ("1e-3 s", "0.0011 s", 1),
        ("1e-3 s", "0.0021 s", 0),
        ("wrote calib.json", "wrote calib.json.bak", 0),  # the whole line
    ],
)
def test_a_printed_line_matches_by_the_docs_rule(expected, actual, same):
    """conftest.py's rule for a docs block's output: text and spacing, `...`, integers exact,
    decimals within one unit of the last printed digit; each case on both sides of its edge."""
    assert _docs_conftest().line_matches(expected, actual) is bool(same)


def test_printed_output_is_found_in_order_and_a_stale_line_is_named():
    conftest = _docs_conftest()
    output = "a 1\nnoise\nb 2.50\nc 3\n"
    conftest.check_output(["a 1", "...", "b 2.5", "c 3"], output, "page")
    with pytest.raises(AssertionError, match="the docs show the line\n  b 2.5"):
        conftest.check_output(["c 3", "b 2.5"], output, "page")  # out of order
    with pytest.raises(AssertionError, match="12 poses"):
        conftest.check_output(["12 poses"], "13 poses\n", "page")


def test_a_console_block_splits_into_commands_and_their_output():
    commands = _docs_conftest().console_commands(
        "$ ftkin a \\\n    --b 1\nout 1\n...\n$ ftkin c   # why\nout 2\n"
    )
    assert commands == [("ftkin a \\\n    --b 1", ["out 1", "..."]), ("ftkin c   # why", ["out 2"])]


REFERENCE = re.compile(
    r"(?<![\w/.])(?<!new file `)((?:ftkin|tests|benchmarks|scripts|urdf|docs)/[\w./*-]*\w)"
)
MADE_BY_MAKE_DOCS = ("docs/_build", "docs/api", "api/")  # sphinx-build and docs/api_pages.py
LINK = re.compile(r"\]\((?!https?:|#|mailto:)(?P<target>[^)#\s]+)")


def test_every_file_and_page_the_docs_name_exists():
    """A path of the repository named in README or docs (``tests/robot/rtde_controller.py``,
    ``benchmarks/results/...``), and every local link, is there."""
    missing = []
    for page in PAGES:
        text = page.read_text()
        for path in REFERENCE.findall(text):
            placeholder = "*" in path or "_X." in path  # bench_*.py, bench_X.py
            if (
                not (ROOT / path).exists()
                and not placeholder
                and not path.startswith(MADE_BY_MAKE_DOCS)
            ):
                missing.append(f"{page.name}: {path}")
        for link in LINK.finditer(text):
            made = link["target"].startswith(MADE_BY_MAKE_DOCS)
            if not (page.parent / link["target"]).exists() and not made:
                missing.append(f"{page.name}: link {link['target']}")
    assert not missing, "\n".join(sorted(set(missing)))
