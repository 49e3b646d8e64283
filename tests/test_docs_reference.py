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
import re
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
