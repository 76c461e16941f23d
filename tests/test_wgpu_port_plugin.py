"""The WebGPU port (ports/wgpu) judged through vlref's pytest plugin, as a port team's own test suite would:
one `vlref_compare` call per pass, against `vlref march` on the port's exported buffers, each under the preset
its formats call for (kz_check.PASSES). A failure names the comparison's report.html; the session's
comparisons are listed in vlref-report/summary.html (tests/test_pytest_plugin.py tests the plugin itself)."""

import sys
from pathlib import Path

import pytest

PORT_DIR = Path(__file__).resolve().parents[1] / "ports" / "wgpu"
sys.path.insert(0, str(PORT_DIR))

import kz_check  # noqa: E402
import kz_port  # noqa: E402
import kz_scene  # noqa: E402

SIZE = ("render.width=160", "render.height=90", "render.steps=16")


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """The faithful port rendered once: ``(port.toml, {pass: array})``."""
    try:
        dev = kz_port.device()
    except kz_port.NoAdapter as exc:
        pytest.skip(f"no WebGPU adapter, so no GPU port can run here (CI installs mesa-vulkan-drivers): {exc}")
    port = kz_port.KillzonePort(kz_scene.load(str(kz_check.SCENE), SIZE), dev)
    passes = port.run("faithful")
    return kz_port.export(port, tmp_path_factory.mktemp("wgpu") / "port", str(kz_check.SCENE), SIZE, passes), passes


@pytest.mark.parametrize("port_pass, buffer, preset", kz_check.PASSES)
def test_port_pass(exported, vlref_compare, port_pass, buffer, preset):
    manifest, passes = exported
    report = vlref_compare(passes[port_pass], buffer, port=manifest, preset=preset or "gpu-half",  # fp16 targets
                           ignore_sky=port_pass == "depth_lo")
    assert report.metrics["failing_pixels"] == 0 and report.metrics["compared_pixels"] > 1000
