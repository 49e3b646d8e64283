"""meshcat's static page with its scene commands inlined (run in order, before the load event)."""

from __future__ import annotations

import base64

import pytest

from ftkin.viz.legend import inline_commands


def _fetch(data: bytes) -> str:
    return (
        '\nfetch("data:application/octet-binary;base64,' + base64.b64encode(data).decode() + '")\n'
        "    .then(res => res.arrayBuffer())\n"
        "    .then(buffer => viewer.handle_command_bytearray(new Uint8Array(buffer)));\n"
    )


def test_fetches_become_direct_calls_in_order():
    page = (
        '<script>var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));'
        + _fetch(b"first")
        + _fetch(b"\x00\xffsecond")
        + "</script>"
    )
    out = inline_commands(page)
    assert "fetch(" not in out
    assert out.index("function ftkinCommand") < out.index("var viewer = new MeshCat.Viewer(")
    calls = [part.split('");')[0] for part in out.split('ftkinCommand("')[1:]]
    assert [base64.b64decode(c) for c in calls] == [b"first", b"\x00\xffsecond"]


def test_a_page_without_commands_is_unchanged():
    assert inline_commands("<html>hi</html>") == "<html>hi</html>"


def test_a_real_meshcat_page_keeps_no_fetch_of_data(arm):
    pytest.importorskip("meshcat")
    from ftkin import SensorModel
    from ftkin.viz import CalibrationViewer

    with CalibrationViewer(SensorModel.from_tool(0.3, [0.0, 0.0, 0.05]), arm) as viewer:
        viewer.show_pose([0.3, 0.2, -0.3, 0.0, 0.2, 0.0], [0.0, 0.0, -3.0, 0.0, 0.0, 0.0])
        raw = viewer.visualizer.static_html()
        page = viewer.static_html()
    assert raw.count('fetch("data:') > 10
    assert 'fetch("data:' not in page
    assert page.count('ftkinCommand("') == raw.count('fetch("data:')
