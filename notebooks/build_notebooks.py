"""Write the notebooks of this folder from the cell sources below, with empty outputs.

    python notebooks/build_notebooks.py

The ``.ipynb`` files are generated: edit this script, not the notebooks, and re-run it. Outputs are
never stored (run the notebooks, or ``pytest --nbmake notebooks``, to see them).
"""

from __future__ import annotations

from pathlib import Path

import nbformat
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

HERE = Path(__file__).resolve().parent

SETUP = """\
import dataclasses
import time

import matplotlib.pyplot as plt
import numpy as np

import vlref
from vlref.notebook import display_buffer, display_rgb, plot_images
from vlref.render import render
from vlref.scene import bundled_scenes, load_scene

print("vlref", vlref.__version__)"""

QUICKSTART = [
    ("md", """\
# vlref quick start

vlref renders volumetric lighting ("god rays") on the CPU: the physically based single-scattering
march (`physical`) and faithful versions of real-time techniques (`killzone`, `slightlymad`, `urp`,
`radial`). This notebook loads a bundled scene, renders it, shows the main buffers side by side, then
changes one parameter and renders again.

Every image is linear HDR; the previews here are tone-mapped like vlref's PNG previews (exposure, ACES
filmic fit, sRGB)."""),
    ("code", SETUP),
    ("md", "## The bundled scenes"),
    ("code", """\
for name, path in bundled_scenes().items():
    print(f"{name:<18s} {load_scene(name).description}")"""),
    ("md", """\
## Load and render

`load_scene` takes a bundled name or a path, and override strings `key.path=value` (the CLI's `--set`).
A 320×180 frame renders in a few seconds (the first call also compiles the Numba kernels)."""),
    ("code", """\
scene = load_scene("pillars", ["render.width=320", "render.height=180"])
print(scene.description)
print("technique:", scene.render.technique, "| medium:", scene.medium)

result = render(scene, stages=True)
print({stage: f"{seconds:.2f} s" for stage, seconds in result.timings.items()})
print(sorted(result.buffers))"""),
    ("md", """\
## The buffers

* `final`: the composited frame `scene_colour · transmittance + inscatter`;
* `depth`: linear eye depth in metres, shown on a log scale (grey = sky, no hit);
* `inscatter`: light scattered toward the camera by the medium;
* `transmittance`: the fraction of the surface's light that reaches the camera;
* `shadow_spot_0`: the spot light's shadow map (distance from the light; grey = nothing within range)."""),
    ("code", """\
b = result.buffers
exposure = 1.0 / np.percentile(b["final"].max(axis=2), 99)
fig = plot_images({
    "final": display_buffer(b["final"], exposure),
    "depth (log scale)": display_buffer(np.log(b["depth"])),
    "inscatter": display_buffer(b["inscatter"], exposure),
    "transmittance": display_buffer(b["transmittance"], vmin=0.0, vmax=1.0),
    "shadow map of the spot light": display_buffer(b["shadow_spot_0"]),
    "scene colour (no medium)": display_buffer(b["scene_colour"], exposure),
}, ncols=3)
plt.show()"""),
    ("md", """\
## Change one parameter and re-render

The scene is a tree of frozen dataclasses: `scene.replace(...)` with `dataclasses.replace` makes a
changed copy (or pass another override string to `load_scene`). Here the Henyey-Greenstein
anisotropy `g` goes from forward scattering (0.5) to back scattering (-0.5): the shafts seen against
the light dim, since the camera looks toward the spot light. Both frames share one exposure."""),
    ("code", """\
back = scene.replace(medium=dataclasses.replace(scene.medium, anisotropy=-0.5))
result_back = render(back)
fig = plot_images({
    f"g = {scene.medium.anisotropy}": display_rgb(result.buffers["final"], exposure),
    f"g = {back.medium.anisotropy}": display_rgb(result_back.buffers["final"], exposure),
}, ncols=2, width=5)
plt.show()
ratio = result_back.buffers["inscatter"].sum() / result.buffers["inscatter"].sum()
print(f"total inscatter with g = -0.5 is {ratio:.2f} x the g = 0.5 total")"""),
    ("md", """\
## Another technique

`render.technique` switches the volumetric passes; everything else stays. The `killzone` technique
marches at half resolution with a Bayer offset, then upsamples and blurs (its stage buffers come back
with `stages=True`)."""),
    ("code", """\
kz = render(load_scene("pillars", ["render.width=320", "render.height=180", "render.technique=killzone"]),
            stages=True)
kz_exposure = 1.0 / np.percentile(kz.buffers["final"].max(axis=2), 99)
fig = plot_images({name: display_buffer(kz.buffers[name], kz_exposure)
                   for name in ("march_half", "upsample", "final")}, ncols=3)
plt.show()"""),
    ("md", """\
Next: `02_parameter_explorer.ipynb` (sliders), `03_validating_a_port.ipynb` (compare a port's image
with the reference), `04_physics.ipynb` (convergence and bias). From a shell, `vlref render pillars`
writes the same buffers as EXR files."""),
]

EXPLORER = [
    ("md", """\
# Parameter explorer

Turn the knobs and watch the frame: medium (scattering, absorption, anisotropy `g`), light power,
march (steps, offset pattern, resolution), post (blur, VL's depth downsample that feeds its upsample)
and the technique. Under the image: the inscatter along one scanline and the phase function of the
current `g`.

The preview is 320×180. The frame's geometry, G-buffer, shadow maps and scene colour are built once
per scene (`vlref.notebook.PreviewRenderer`) and reused while only the medium, march, post settings,
technique or light power change: shadow maps depend on the lights' placement and the geometry, never
on the medium. The reused frame gives bit-identical buffers to a full `render`
(`tests/test_notebook_helpers.py`).

Without a live kernel (CI, `pytest --nbmake`, or `VLREF_STATIC=1`) the controls fall back to one
static render with their default values."""),
    ("code", SETUP + """
import io
import itertools

from IPython.display import Image, display
from matplotlib.figure import Figure

from vlref.errors import InputError
from vlref.notebook import Choice, PreviewRenderer, Slider, Toggle, interact_or_static, live_widgets, \\
    scaled_light_intensity, time_call
from vlref.phase import hg_array
from vlref.techniques import TECHNIQUES

print("live widgets:", live_widgets())"""),
    ("md", """\
## How the controls map onto each technique

The technique control lists every registered technique (`vlref.techniques.TECHNIQUES`).

| control | physical, killzone | slightlymad | urp | radial | froxel |
|---|---|---|---|---|---|
| scattering σs, absorption σa | `medium` | `medium` (`techniques.slightlymad.medium = "scene"`) | — (no density) | — | `medium` |
| anisotropy g | `medium.anisotropy` | `medium.anisotropy` (same switch) | `scattering = -g` (the tutorial's sign) | — | `medium.anisotropy` |
| light power | every light's `intensity` × factor | same | same | same | same |
| steps | `render.steps` | `render.steps` (≤ 64) | `render.steps` (≥ 2) | — | light leg: `ceil(sqrt(steps))` |
| sampling | `render.sampling` (killzone: no `hash`) | `dither` (`none`/`bayer4`/`bayer8`) | — (own jitter) | — | — (own jitter) |
| resolution | killzone: `render.resolution` (physical: full) | `render.resolution` | `render.resolution` | — | — (own grid) |
| blur | killzone `blur` | `blur` | `gauss_samples = 0` when off | — | — |
| VL depth downsample | — | `depth_downsample` | — | — | — |

A setting a technique cannot take (e.g. `third` resolution for killzone, `urp` on a scene without a
directional light) shows the error vlref raises instead of an image."""),
    ("code", """\
SIZE = ["render.width=320", "render.height=180"]
SCENES = {name: load_scene(name, SIZE) for name in ("pillars", "window", "coloured_lights", "urp_sun")}
DITHER = {"none": "none", "bayer4": "4x4", "bayer8": "8x8"}


def explorer_scene(scene, technique, scattering, absorption, anisotropy, power, steps, sampling, resolution,
                   blur, vl_depth):
    \"\"\"The bundled scene ``scene`` with the explorer's settings applied (table above).\"\"\"
    s = scaled_light_intensity(SCENES[scene], power)
    s = s.replace(medium=dataclasses.replace(s.medium, scattering=scattering, absorption=absorption,
                                             anisotropy=anisotropy),
                  render=dataclasses.replace(s.render, technique=technique, steps=steps, sampling=sampling,
                                             resolution=resolution))
    t = s.techniques
    if technique == "slightlymad" and sampling not in DITHER:
        raise InputError("<explorer>", "sampling", f"slightlymad dithers with {', '.join(DITHER)} only")
    return s.replace(techniques=dataclasses.replace(
        t,
        killzone=dataclasses.replace(t.killzone, blur=blur),
        slightlymad=dataclasses.replace(t.slightlymad, medium="scene", blur=blur, depth_downsample=vl_depth,
                                        dither=DITHER.get(sampling, "none")),
        urp=dataclasses.replace(t.urp, anisotropy=anisotropy, gauss_samples=t.urp.gauss_samples if blur else 0)))


preview = PreviewRenderer()
EXPOSURE = {}  # per scene: fixed by its first render, so that brightness changes stay visible


def base_exposure(scene, buffers):
    if scene not in EXPOSURE:
        EXPOSURE[scene] = 1.0 / max(np.percentile(buffers["final"].max(axis=2), 99), 1e-12)
    return EXPOSURE[scene]"""),
    ("md", """\
## Re-render time

The benchmark the explorer is built for: 320×180, 16 steps, half resolution, `killzone`; each call
changes the medium (a new scene object) and reuses the frame. `physical` has no resolution option
(it marches every pixel), so its time is for the full 320×180."""),
    ("code", """\
scatterings = iter(np.linspace(0.02, 0.2, 1000))


def rerender(technique):
    scene = explorer_scene("pillars", technique, next(scatterings), 0.01, 0.5, 1.0, 16, "bayer4", "half", True,
                           "chessboard")
    return preview.render(scene)


for technique in ("killzone", "physical"):
    _, timing = time_call(lambda: rerender(technique), repeat=5, warmup=1)
    print(f"{technique:<9s} 320x180, 16 steps, half res, frame reused: {timing}")
print("frame rebuilds so far:", preview.rebuilds)"""),
    ("md", """\
## The explorer

Sliders update the image when released. The red line on the image marks the scanline plotted
below it; the line above the image counts the renders (`render #N`), so a change that did not re-render
shows."""),
    ("code", """\
CONTROLS = {
    "scene": Choice(tuple(SCENES), "pillars"),
    "technique": Choice(tuple(TECHNIQUES), "killzone"),
    "scattering": Slider(0.0, 0.5, 0.08, step=0.005, description="scattering σs (1/m)"),
    "absorption": Slider(0.0, 0.5, 0.01, step=0.005, description="absorption σa (1/m)"),
    "anisotropy": Slider(-0.95, 0.95, 0.5, step=0.05, description="anisotropy g"),
    "power": Slider(0.05, 20.0, 1.0, log=True, description="light power ×"),
    "steps": Slider(2, 64, 16, integer=True, description="steps"),
    "sampling": Choice(("none", "bayer2", "bayer4", "bayer8", "hash"), "bayer4"),
    "resolution": Choice(("full", "half", "third", "quarter"), "half"),
    "blur": Toggle(True, "blur"),
    "vl_depth": Choice(("chessboard", "min", "max"), "chessboard", "VL depth downsample"),
    "exposure_ev": Slider(-4.0, 4.0, 0.0, step=0.25, description="exposure (EV)"),
    "row": Slider(0, 179, 100, integer=True, description="scanline row"),
}
renders = itertools.count(1)


def show(scene, technique, scattering, absorption, anisotropy, power, steps, sampling, resolution, blur, vl_depth,
         exposure_ev, row):
    try:
        s = explorer_scene(scene, technique, scattering, absorption, anisotropy, power, steps, sampling,
                           resolution, blur, vl_depth)
        start = time.perf_counter()
        buffers = preview.render(s)
        seconds = time.perf_counter() - start
    except InputError as exc:
        print("cannot render this combination:", exc)
        return None
    print(f"render #{next(renders)}: {scene}, {technique}, {1e3 * seconds:.0f} ms")
    exposure = base_exposure(scene, buffers) * 2.0 ** exposure_ev
    fig = Figure(figsize=(11, 6.4))   # not pyplot's: widget callbacks run in a kernel subshell thread, and
    grid = fig.add_gridspec(2, 2, height_ratios=(2.2, 1), width_ratios=(2.4, 1))
    ax = fig.add_subplot(grid[0, :])
    ax.imshow(display_rgb(buffers["final"], exposure))
    ax.axhline(row, color="red", lw=0.8)
    ax.set_title(f"{technique}: rendered in {1e3 * seconds:.0f} ms (frame reused)", fontsize=10)
    ax.axis("off")
    line = fig.add_subplot(grid[1, 0])
    for c, colour in enumerate("rgb"):
        line.plot(buffers["inscatter"][row, :, c], color=colour, lw=1)
    line.set_xlabel("pixel column")
    line.set_ylabel("inscatter radiance")
    line.set_title(f"inscatter along row {row}", fontsize=10)
    polar = fig.add_subplot(grid[1, 1], projection="polar")
    theta = np.linspace(0.0, 2.0 * np.pi, 721)
    polar.plot(theta, 4.0 * np.pi * hg_array(np.cos(theta), anisotropy))
    polar.set_title(f"HG phase × 4π, g = {anisotropy:+.2f}", fontsize=10)
    polar.set_yticklabels([])
    fig.tight_layout()                # pyplot's close('all') of a cell ending there blanked a figure being drawn;
    png = io.BytesIO()                # PNG bytes: no dependence on matplotlib-inline's figure formatter
    fig.savefig(png, format="png", dpi=80)
    display(Image(png.getvalue()))
    return buffers


explorer = interact_or_static(show, CONTROLS)"""),
    ("md", """\
Ideas to try: push `g` toward 0.9 and watch the halo around the light source narrow; set steps to 4
with `sampling = none` (banding) and then `bayer4` (noise that the blur hides); switch `resolution`
to `quarter` and look at the pillars' silhouettes; switch the `VL depth downsample` of
`slightlymad` between `min` and `max` to see which side of an edge its upsample trusts."""),
]

PORT = [
    ("md", """\
# Validating a port

You ported a technique to a GPU (or to another engine) and want to know whether its image matches
vlref. `vlref compare` (and `vlref.oracle.compare_files` from Python) answers pass/fail under a
tolerance preset, with heat maps and a report.

The bundled example (`data/examples`, made by `python -m vlref.notebook`) holds a float64 reference of
the `pillars` scene (160×90, `physical`, 32 steps), a float32 port of it with a **planted bug**, the
same float32 port without the bug, and the depth buffer."""),
    ("code", SETUP + """
import json
import tempfile
from pathlib import Path

from IPython.display import HTML, display

from vlref.io.images import read_image
from vlref.notebook import EXAMPLE_FILES, display_scalar, examples_dir
from vlref.oracle import compare_files, load_presets
from vlref.oracle.report import colour_map, heat_top, json_ready, render_html

folder = examples_dir()
files = {key: folder / name for key, name in EXAMPLE_FILES.items()}
images = {key: read_image(path) for key, path in files.items()}
for key, img in images.items():
    print(f"{key:<11s} {files[key].name:<15s} {img.shape} {img.dtype}")"""),
    ("code", """\
exposure = 1.0 / np.percentile(images["reference"].max(axis=2), 99)
fig = plot_images({"reference (float64)": display_rgb(images["reference"], exposure),
                   "port with the bug (float32)": display_rgb(images["port_bug"], exposure),
                   "depth (grey = sky)": display_scalar(images["depth"][:, :, 0])}, ncols=3)
plt.show()"""),
    ("md", """\
## The tolerance presets

A pixel fails when `|test - ref| > abs_tol·S + rel_tol·|ref|` in any channel; the image passes when the
failing fraction and the mean absolute error are within their bounds (`S` is 1, or the mean `|ref|` for
presets with `scale = "mean"`). Pick the preset that matches your port: `float32` for an IEEE float32
port at full resolution, `gpu-full`/`gpu-half`/`gpu-quarter` for fp16 render targets and low-resolution
marches."""),
    ("code", """\
for name, tol in load_presets().items():
    print(f"{name:<12s} rel_tol {tol.rel_tol:<7g} abs_tol {tol.abs_tol:<7g} fail ≤ {tol.max_fail_fraction:<6g}"
          f" mean ≤ {tol.max_mean_abs:<7g} ({tol.scale})  {tol.description}")"""),
    ("md", "## Compare the port with the reference"),
    ("code", """\
report = compare_files(files["reference"], files["port_bug"], "float32")
print(report.summary())"""),
    ("md", """\
The full report (what `vlref compare -o DIR` writes as `report.json`):"""),
    ("code", """\
print(json.dumps(json_ready(report.to_dict()), indent=1)[:2500])"""),
    ("md", """\
## Heat map, failing pixels, signed error

The heat map shows `max_c |test - ref|` scaled so that its 99th percentile is the top of the ramp;
failing pixels are red on the darkened reference. The signed error (test minus reference, luminance)
tells *how* the port is wrong."""),
    ("code", """\
err = np.abs(report.test - report.ref).max(axis=2)
overlay = (display_rgb(report.ref, exposure) * 0.3).astype(np.uint8)
overlay[report.fail] = (255, 32, 32)
fig = plot_images({f"heat map (top = {heat_top(report):.3g})": colour_map(err / heat_top(report)),
                   f"failing pixels: {report.metrics['failing_pixels']} of {report.fail.size}": overlay},
                  ncols=2, width=5)
plt.show()

signed = (report.test - report.ref).mean(axis=2)
limit = np.percentile(np.abs(signed), 99)  # larger errors saturate
fig, ax = plt.subplots(figsize=(6, 3.6))
im = ax.imshow(signed, cmap="RdBu_r", vmin=-limit, vmax=limit)
ax.set_title(f"test - reference (mean over RGB), {100 * np.mean(signed < 0):.0f}% of pixels too dark")
ax.axis("off")
fig.colorbar(im, ax=ax, shrink=0.8)
plt.show()"""),
    ("md", """\
**Reading it.** The port is too dark wherever the shafts are seen, most of all beside the pillars
near the spot light, where the camera looks almost straight into the light. The errors follow the
angle between the view and the light, not the geometry, so the phase function is the suspect; a
port that is darkest exactly where forward scattering should peak has turned it into back
scattering: it evaluates the Henyey-Greenstein phase function with the light vector reversed,
`p(dot(d, -l); g) = p(dot(d, l); -g)` (vlref's convention: `cos θ = dot(d, l)`, `d` the view
direction, `l` toward the light, see `vlref/phase.py`). Mitsuba, for one, writes its direction
vectors the other way round, which makes this an easy slip in a port.

## The fixed port

The same float32 port with the sign fixed passes `float32`: its differences are float32 rounding, a
few knife-edge pixels aside (decisions such as a shadow-map depth test may flip in float32; the preset
allows 1 pixel in 1000)."""),
    ("code", """\
fixed = compare_files(files["reference"], files["port_fixed"], "float32")
print(fixed.summary())

rel = lambda r: (np.abs(r.test - r.ref) / np.maximum(np.abs(r.ref), 1e-6)).ravel()
fig, ax = plt.subplots(figsize=(7, 3))
bins = np.logspace(-10, 1, 60)
ax.hist(rel(fixed), bins=bins, alpha=0.7, label="fixed port")
ax.hist(rel(report), bins=bins, alpha=0.7, label="port with the bug")
ax.axvline(fixed.tolerance.rel_tol, color="k", ls="--", lw=1, label="float32 rel_tol")
ax.set_xscale("log")
ax.set_xlabel("relative error per value")
ax.legend()
plt.show()"""),
    ("md", """\
## Masks

Sky pixels, borders or a user mask can be left out of the comparison. Here the sky (infinite depth in
`depth.exr`) is ignored, the same as `vlref compare --ignore-sky depth.exr`. The shafts cross the sky
in this frame, so leaving it out would hide part of the bug: choose masks with care."""),
    ("code", """\
masked = compare_files(files["reference"], files["port_bug"], "float32", ignore_sky=str(files["depth"]))
print(masked.summary())"""),
    ("md", """\
## The report files

`compare_files(..., out_dir=...)` (or `vlref compare REF TEST -o DIR`) writes `report.json`,
`diff.exr`, `heatmap.png`, `flip.png` and a self-contained `report.html`, shown below."""),
    ("code", """\
with tempfile.TemporaryDirectory() as tmp:
    compare_files(files["reference"], files["port_bug"], "float32", out_dir=tmp)
    print(sorted(p.name for p in Path(tmp).iterdir()))
display(HTML(render_html(report)))"""),
]

PHYSICS = [
    ("md", """\
# The physics behind the images

Small frames (64×36, 512² shadow maps) so that this runs in well under two minutes:

1. each technique's convergence to the quadrature reference as the step count grows (log-log, with
   the fitted slope: about -1 for a first-order march);
2. the bias image of each technique (its error at 64 steps, where the step error is small);
3. Henyey-Greenstein phase functions;
4. the effect of the Bayer offset pattern and of the blur on the error.

The reference (`vlref.reference.render_reference`) solves the single-scattering integral per pixel
with adaptive Gauss-Kronrod quadrature to a stated tolerance, with exact shadow rays; its own error
bound is printed."""),
    ("code", SETUP + """
from scipy.integrate import quad

from vlref.notebook import display_scalar
from vlref.phase import hg_array
from vlref.reference import render_reference, technique_bias

SMALL = ["render.width=64", "render.height=36", "lights.0.shadows.resolution=512"]
scene = load_scene("urp_sun", SMALL)
print(scene.description)
start = time.perf_counter()
ref = render_reference(scene, rel_tol=1e-4)
print(f"reference in {time.perf_counter() - start:.1f} s, error bound {ref.max_error:.2e}, "
      f"max inscatter {ref.inscatter.max():.3g}")"""),
    ("md", """\
## Convergence with the step count

`technique_bias` renders the scene's inscatter with a technique at each step count and compares it
with the reference (`mean_rel` = error mass over signal mass). Besides each technique as its source
ships it, two variants remove approximations:

* `killzone, exact`: full-resolution march, no blur, exact shadow rays instead of one shadow-map tap;
* `slightlymad, matched`: the scene's medium instead of VolumetricLights' own constants
  (`ScatteringCoef`, `ExtinctionCoef`, `MieG`): `techniques.slightlymad.medium = "scene"`.

A first-order march converges with slope -1. Whatever stays flat is bias: the technique computes
something else than the single-scattering integral."""),
    ("code", """\
tp = scene.techniques
VARIANTS = {
    "physical": ("physical", scene),
    "killzone": ("killzone", scene),
    "killzone, exact": ("killzone", scene.replace(
        lights=tuple(dataclasses.replace(l, shadows=dataclasses.replace(l.shadows, filter="exact"))
                     for l in scene.lights),
        techniques=dataclasses.replace(tp, killzone=dataclasses.replace(
            tp.killzone, resolution="full", blur=False, shadow_filter="exact")))),
    "slightlymad": ("slightlymad", scene),
    "slightlymad, matched": ("slightlymad", scene.replace(techniques=dataclasses.replace(
        tp, slightlymad=dataclasses.replace(tp.slightlymad, medium="scene")))),
    "urp": ("urp", scene),
}
STEPS = (64, 32, 16, 8, 4)  # the first entry gives the bias image
bias = {}
for label, (technique, variant) in VARIANTS.items():
    start = time.perf_counter()
    bias[label] = technique_bias(variant, technique, steps_list=STEPS, reference=ref)
    errors = ", ".join(f"{r['mean_rel']:.4f}" for r in sorted(bias[label].table, key=lambda r: r["steps"]))
    print(f"{label:<21s} slope {bias[label].slope:+.2f}   mean_rel at 4..64 steps: {errors}"
          f"   ({time.perf_counter() - start:.1f} s)")

fig, ax = plt.subplots(figsize=(7, 4.8))
for label, rep in bias.items():
    rows = sorted(rep.table, key=lambda r: r["steps"])
    steps = np.array([r["steps"] for r in rows])
    errors = np.array([r["mean_rel"] for r in rows])
    ax.loglog(steps, errors, "o-", label=f"{label} (slope {rep.slope:+.2f})")
first = sorted(bias["physical"].table, key=lambda r: r["steps"])[0]["mean_rel"]
ax.loglog(steps, first * (steps / steps[0]) ** -1.0, "k:", lw=1, label="slope -1")
ax.set_xlabel("steps")
ax.set_ylabel("mean relative error (error mass / signal mass)")
ax.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.0, 0.5))
ax.grid(True, which="both", alpha=0.3)
plt.show()"""),
    ("md", """\
## Bias images

Per pixel `max_c |L - R|` at 64 steps, each on its own scale (0 to its 99th percentile). Where the
error sits (shadow edges, depth edges, the sky) says what the technique approximates; the titles give
the share of the error mass on depth edges."""),
    ("code", """\
exposure = 1.0 / np.percentile(ref.inscatter.max(axis=2), 99)
panels = {"reference inscatter": display_rgb(ref.inscatter, exposure)}
for label, rep in bias.items():
    c = rep.concentration
    panels[f"{label}: {rep.mean_rel:.3g}, {100 * c['depth_edges']:.0f}% depth edges"] = \\
        display_scalar(rep.error, vmin=0.0)
fig = plot_images(panels, ncols=4, width=3.6)
plt.show()"""),
    ("md", """\
## Henyey-Greenstein phase function

`p(cos θ; g) = (1 - g²) / (4π (1 + g² - 2g cos θ)^{3/2})`, with θ the angle between the view direction
and the direction toward the light: `g > 0` throws light forward, toward a viewer looking into the
light. Each lobe integrates to 1 over the sphere (checked numerically below)."""),
    ("code", """\
theta = np.linspace(0.0, 2.0 * np.pi, 1441)
fig, axes = plt.subplots(1, 2, figsize=(10, 4.2), subplot_kw={"projection": "polar"})
for g in (-0.5, 0.0, 0.3, 0.6):
    p = hg_array(np.cos(theta), g)
    axes[0].plot(theta, 4.0 * np.pi * p, label=f"g = {g}")
    axes[1].plot(theta, np.log10(4.0 * np.pi * p) + 2.0, label=f"g = {g}")
axes[0].set_title("4π·p (linear)")
axes[1].set_title("log10(4π·p) + 2")
axes[0].legend(loc="lower left", fontsize=8, bbox_to_anchor=(-0.25, -0.15))
plt.show()

for g in (-0.5, 0.0, 0.3, 0.6, 0.9):
    integral, _ = quad(lambda mu: hg_array(mu, g), -1.0, 1.0, points=[1.0])
    print(f"g = {g:+.1f}: 2π ∫ p dμ = {2.0 * np.pi * integral:.8f}")"""),
    ("md", """\
## Bayer size and blur

At a low step count each pixel's start offset decides how the error looks: no offset gives banding
(every pixel samples the same depths), a Bayer pattern trades the bands for a fine pattern, and the
bilateral blur averages that pattern, at the price of smearing the shafts' edges. `killzone` at 8
steps (half resolution, its default); the numbers say which effect wins on this frame."""),
    ("code", """\
rows = []
images = {}
for sampling in ("none", "bayer2", "bayer4", "bayer8"):
    for blur in (False, True):
        s = load_scene("urp_sun", SMALL + ["render.technique=killzone", "render.steps=8",
                                           f"render.sampling={sampling}",
                                           f"techniques.killzone.blur={'true' if blur else 'false'}"])
        inscatter = render(s).buffers["inscatter"]
        e = np.abs(inscatter - ref.inscatter).max(axis=2)
        rows.append((sampling, blur, e.sum() / ref.inscatter.max(axis=2).sum()))
        if sampling in ("none", "bayer4"):
            images[f"{sampling}, blur {'on' if blur else 'off'}"] = display_rgb(inscatter, exposure)

labels = [s for s, _, _ in rows[::2]]
x = np.arange(len(labels))
fig, ax = plt.subplots(figsize=(6.5, 3.4))
ax.bar(x - 0.2, [v for _, b, v in rows if not b], 0.4, label="no blur")
ax.bar(x + 0.2, [v for _, b, v in rows if b], 0.4, label="blur")
ax.set_xticks(x, labels)
ax.set_ylabel("mean relative error")
ax.legend()
plt.show()
for sampling, blur, value in rows:
    print(f"{sampling:<7s} blur {'on ' if blur else 'off'}  mean relative error {value:.4f}")
fig = plot_images(images, ncols=4, width=3.2)
plt.show()"""),
]

SWEEPS = [
    ("md", """\
# Sweeps on Dask

`vlref sweep` renders every technique at every point of a parameter grid and measures each image
against the quadrature reference. The (point, technique) items are independent, so they run on a Dask
cluster: here a `LocalCluster` of two worker processes (`scheduler="local:2"`, the CLI's
`--scheduler local:2`); `tcp://host:port` would use an existing scheduler. The output folder holds the
same bytes whatever the scheduler; render times go to a separate `timings.csv`.

Small frames (64×36) keep this to a few seconds of work; the cluster's start (two Python processes
loading the compiled kernels) is most of the time."""),
    ("code", """\
import csv
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

from vlref.sweep import load_sweep, run_sweep

folder = Path(tempfile.mkdtemp())
(folder / "sweep.toml").write_text('''
scene = "urp_sun"
set = ["render.width=64", "render.height=36", "lights.0.shadows.resolution=512"]
techniques = ["physical", "killzone", "urp"]
metrics = ["error", "time"]
rel_tol = 1e-4
[grid]
"render.steps" = [4, 8, 16, 32]
''')
spec = load_sweep(folder / "sweep.toml")
rows = run_sweep(spec, folder / "out", scheduler="local:2")
print(sorted(p.name for p in (folder / "out").iterdir()))
print((folder / "out" / "summary.csv").read_text())"""),
    ("md", """\
## Error against steps, per technique

`mean_rel` is the error mass over the signal mass (`vlref.reference.bias.inscatter_error`). The
physical march falls with slope -1 (first order); what stays flat is each technique's bias."""),
    ("code", """\
fig, ax = plt.subplots(figsize=(6.5, 4.2))
for technique in spec.techniques:
    mine = sorted((r for r in rows if r["technique"] == technique), key=lambda r: r["render.steps"])
    ax.loglog([r["render.steps"] for r in mine], [r["mean_rel"] for r in mine], "o-", label=technique)
ax.set_xlabel("steps")
ax.set_ylabel("mean relative error")
ax.grid(True, which="both", alpha=0.3)
ax.legend()
plt.show()
times = list(csv.DictReader((folder / "out" / "timings.csv").read_text().splitlines()))
print("\\n".join(f"{t['item']:<14s} {float(t['seconds']):.2f} s" for t in times))"""),
]


FROXEL = [
    ("md", """\
# Froxel volumetrics and temporal reprojection

The `froxel` technique (Wronski 2014, Hillaire 2015; docs/TECHNIQUES.md) lights a camera-aligned grid,
integrates it front to back and looks it up per pixel. Below: the grid converging to the physical march
as it refines, a slice of the exported grid, and the temporal history of an animated scene. Everything
runs at 64x36 so the notebook stays cheap."""),
    ("code", SETUP),
    ("code", """\
size = ["render.width=64", "render.height=36", "lights.0.shadows.resolution=128"]
ref = render(load_scene("pillars", size + ["render.steps=128", 'render.sampling="none"'])).buffers["inscatter"]
panels = {"physical, 128 steps": display_rgb(ref)}
for gw, gh, slices in ((16, 9, 16), (32, 18, 32), (64, 36, 64)):
    grid = [f"techniques.froxel.grid_width={gw}", f"techniques.froxel.grid_height={gh}",
            f"techniques.froxel.slices={slices}", 'techniques.froxel.jitter="none"']
    out = render(load_scene("pillars", size + ['render.technique="froxel"'] + grid)).buffers["inscatter"]
    err = np.abs(out - ref).mean() / ref.mean()
    panels[f"froxel {gw}x{gh}x{slices}: error {err:.3f}"] = display_rgb(out)
fig = plot_images(panels, ncols=4, width=3.2)
plt.show()"""),
    ("md", """\
## The exported grid

`vlref render --stages` writes each grid as an image of stacked slices, `(D·gh, gw, 4)`:
`froxel_scatter` holds `(S, σt)` per froxel, `froxel_integrated` holds `(L, T)` at each slice's far
boundary. `grid_from_image` turns them back into `(gh, gw, D, 4)`."""),
    ("code", """\
from vlref.froxel.grid import grid_from_image

res = render(load_scene("pillars", size + ['render.technique="froxel"', "techniques.froxel.grid_width=32",
                                             "techniques.froxel.grid_height=18", "techniques.froxel.slices=32"]),
             stages=True)
scatter = grid_from_image(res.buffers["froxel_scatter"], 32)
integrated = grid_from_image(res.buffers["froxel_integrated"], 32)
print("slice boundaries (m):", np.round(res.buffers["froxel_slices"][0, :8], 3), "...")
fig = plot_images({f"S, slice {k}": display_rgb(scatter[:, :, k, :3]) for k in (8, 16, 24)}
                  | {"integrated L, last slice": display_rgb(integrated[:, :, -1, :3])}, ncols=4, width=3.2)
plt.show()"""),
    ("md", """\
## Temporal reprojection on an animated scene

`anim_spot` sweeps a spot light with a static camera. With `temporal = true` each frame blends the
reprojected history of the previous one (`froxel_history_frames` counts the frames accumulated); the
error against a per-frame physical march shows the lag (ghosting) of the history."""),
    ("code", """\
from vlref.sequence import render_sequence

small = size + ["techniques.froxel.grid_width=32", "techniques.froxel.grid_height=18", "techniques.froxel.slices=32"]
scene = load_scene("anim_spot", small)
panels = {}
for f, r in render_sequence(scene, range(4)):
    ref_f = render(load_scene("anim_spot", small + ['render.technique="physical"', "render.steps=64",
                                                    f"render.frame={f}"])).buffers["inscatter"]
    err = np.abs(r.buffers["inscatter"] - ref_f).mean() / ref_f.mean()
    panels[f"frame {f}: error {err:.3f}"] = display_rgb(r.buffers["final"])
fig = plot_images(panels, ncols=4, width=3.2)
plt.show()"""),
]


def build(cells) -> nbformat.NotebookNode:
    nb = new_notebook()
    nb.cells = [new_markdown_cell(src) if kind == "md" else new_code_cell(src) for kind, src in cells]
    for i, cell in enumerate(nb.cells):
        cell.id = f"cell-{i:02d}"  # stable ids: rebuilding an unchanged notebook changes no byte
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    nb.metadata["language_info"] = {"name": "python"}
    return nb


NOTEBOOKS = {"01_quickstart.ipynb": QUICKSTART, "02_parameter_explorer.ipynb": EXPLORER,
             "03_validating_a_port.ipynb": PORT, "04_physics.ipynb": PHYSICS, "05_sweeps_on_dask.ipynb": SWEEPS,
             "06_froxel_temporal.ipynb": FROXEL}

if __name__ == "__main__":
    for name, cells in NOTEBOOKS.items():
        nb = build(cells)
        nbformat.validate(nb)
        nbformat.write(nb, HERE / name)
        print("wrote", HERE / name)
