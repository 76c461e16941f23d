"""Helpers for the Jupyter notebooks (``notebooks/``): display arrays, widget-or-static controls,
timing, fast preview re-renders and the bundled port-validation example.

Display
    :func:`display_rgb` tone-maps a linear HDR image exactly as the PNG previews do
    (:func:`vlref.io.tonemap.srgb8`: exposure, ACES filmic fit, sRGB OETF); :func:`auto_exposure` picks the
    exposure that maps the 99th percentile of the brightest channel to 1. :func:`display_scalar`
    normalises a one-channel buffer (depth, shadow-map distances) to [0, 1] with non-finite values
    (sky, empty texels) as NaN, which matplotlib draws in its "bad" colour. :func:`display_buffer`
    picks one of the two by shape; :func:`plot_images` lays titled panels out in a matplotlib figure.

Controls
    :class:`Slider`, :class:`Choice` and :class:`Toggle` describe a control without importing
    ipywidgets. :func:`interact_or_static` turns them into live widgets when a frontend can show them
    (:func:`live_widgets`), and otherwise calls the function once with the controls' values, so a
    headless run (CI, ``pytest --nbmake``) still executes, and raises, top to bottom.

Preview re-rendering
    :class:`PreviewRenderer` keeps the :class:`vlref.render.Frame` (geometry, G-buffer, packed lights,
    scene colour, shadow maps) across calls and rebuilds only what a scene change invalidates:

    * objects, camera or image size -> everything (:func:`vlref.render.prepare_frame`);
    * light colour or intensity, ambient or sky colour -> packed lights and scene colour; the shadow
      maps are kept (they depend on the lights' placement, cone, range and shadow settings, the
      geometry and the camera, never on the medium or the light's power);
    * any other light field -> packed lights, scene colour and shadow maps;
    * medium, march and post settings, technique and its parameters -> nothing: the technique's
      ``render(scene, frame)`` runs on the kept frame.

    Its buffers are bit-identical to :func:`vlref.render.render` of the same scene
    (``tests/test_notebook_helpers.py`` checks it).

Example data
    :func:`make_port_example` writes ``data/examples``: a float64 reference, a float32 "port" with a
    planted bug (the phase function's cosine taken with the light vector reversed, ``p(-cos θ; g)``,
    which equals ``p(cos θ; -g)``), the float32 port without the bug, and the depth buffer.
"""

from __future__ import annotations

import dataclasses
import importlib
import math
import os
import statistics
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from .errors import InputError
from .io.exr import write_exr
from .io.tonemap import srgb8
from .lights import pack_lights
from .lights.shading import scene_colour
from .render import Frame, prepare_frame, render
from .scene import load_scene
from .techniques import TECHNIQUES

__all__ = ["auto_exposure", "display_rgb", "display_scalar", "display_buffer", "plot_images", "Slider", "Choice",
           "Toggle", "live_widgets", "interact_or_static", "Timing", "time_call", "PreviewRenderer", "examples_dir",
           "EXAMPLE_FILES", "make_port_example", "scaled_light_intensity"]


# --------------------------------------------------------------------------- display arrays

def auto_exposure(image: np.ndarray, percentile: float = 99.0) -> float:
    """``1 / q`` with ``q`` the ``percentile`` of the brightest channel over finite pixels; 1 when ``q <= 0``."""
    a = np.asarray(image, dtype=np.float64)
    peak = a.max(axis=2) if a.ndim == 3 else a
    values = peak[np.isfinite(peak)]
    q = float(np.percentile(values, percentile)) if values.size else 0.0
    return 1.0 / q if q > 0.0 else 1.0


def display_rgb(image: np.ndarray, exposure: float | None = None) -> np.ndarray:
    """``(H, W)`` or ``(H, W, 3)`` linear HDR -> ``(H, W, 3)`` uint8 sRGB (:func:`vlref.io.tonemap.srgb8`).

    ``exposure`` None -> :func:`auto_exposure` of the image.
    """
    return srgb8(image, auto_exposure(image) if exposure is None else exposure)


def display_scalar(values: np.ndarray, vmin: float | None = None, vmax: float | None = None,
                   percentiles: tuple[float, float] = (1.0, 99.0)) -> np.ndarray:
    """``(H, W)`` -> float64 in [0, 1]: ``(v - vmin) / (vmax - vmin)`` clipped, non-finite -> NaN.

    Unset bounds are the ``percentiles`` of the finite values (robust against a few outliers);
    a constant image maps to 0.
    """
    a = np.asarray(values, dtype=np.float64)
    finite = np.isfinite(a)
    if finite.any():
        lo_p, hi_p = np.percentile(a[finite], percentiles)
    else:
        lo_p = hi_p = 0.0
    lo = float(lo_p) if vmin is None else float(vmin)
    hi = float(hi_p) if vmax is None else float(vmax)
    scale = hi - lo
    out = np.clip((a - lo) / scale, 0.0, 1.0) if scale > 0 else np.zeros_like(a)
    out[~finite] = np.nan
    return out


def display_buffer(buffer: np.ndarray, exposure: float | None = None, vmin: float | None = None,
                   vmax: float | None = None) -> np.ndarray:
    """A render buffer ready for ``imshow``: ``(H, W, 3)`` -> :func:`display_rgb` (uint8), ``(H, W)`` ->
    :func:`display_scalar` (float in [0, 1], NaN where not finite)."""
    a = np.asarray(buffer)
    if a.ndim == 3 and a.shape[2] == 3:
        return display_rgb(a, exposure)
    if a.ndim == 2:
        return display_scalar(a, vmin, vmax)
    raise ValueError(f"expected an (H, W) or (H, W, 3) buffer, got shape {a.shape}")


def plot_images(images: Mapping[str, np.ndarray], ncols: int = 3, width: float = 4.0, cmap: str = "magma"):
    """A matplotlib figure with one titled panel per image, ``ncols`` to a row.

    uint8 ``(H, W, 3)`` images are shown as they are; float ``(H, W)`` images in [0, 1] (e.g. from
    :func:`display_scalar`) through ``cmap`` with NaN in grey. Returns the figure.
    """
    import matplotlib.pyplot as plt

    if not images:
        raise ValueError("no image to plot")
    n = len(images)
    cols = min(ncols, n)
    rows = -(-n // cols)
    first = next(iter(images.values()))
    aspect = first.shape[0] / first.shape[1]
    fig, axes = plt.subplots(rows, cols, figsize=(width * cols, width * aspect * rows + 0.4 * rows), squeeze=False)
    colours = plt.get_cmap(cmap).with_extremes(bad="0.35")
    for ax, (title, img) in zip(axes.flat, images.items()):
        if img.ndim == 2:
            ax.imshow(img, cmap=colours, vmin=0.0, vmax=1.0, interpolation="nearest")
        else:
            ax.imshow(img, interpolation="nearest")
        ax.set_title(title, fontsize=10)
    for ax in axes.flat:
        ax.axis("off")
    fig.tight_layout()
    return fig


# --------------------------------------------------------------------------- controls

@dataclass(frozen=True)
class Slider:
    """A numeric control on ``[min, max]``; ``log`` spaces it logarithmically (``min > 0``);
    ``integer`` makes an integer slider."""

    min: float
    max: float
    value: float
    step: float | None = None
    description: str = ""
    log: bool = False
    integer: bool = False


@dataclass(frozen=True)
class Choice:
    """A drop-down menu over ``options``."""

    options: tuple
    value: Any
    description: str = ""


@dataclass(frozen=True)
class Toggle:
    """A check box."""

    value: bool
    description: str = ""


Control = Slider | Choice | Toggle


def live_widgets() -> bool:
    """True when controls can be live widgets: an IPython kernel is running, ipywidgets imports, and
    neither ``CI`` nor ``VLREF_STATIC`` is set in the environment.

    A headless executor (nbclient, nbmake) runs a kernel but shows no widget, and an exception inside
    a widget callback is only printed into the widget's output; with ``CI`` set (as CI services and
    ``.ci/run`` do) the notebooks take the static path, where errors propagate.
    """
    if os.environ.get("CI") or os.environ.get("VLREF_STATIC"):
        return False
    ipython = sys.modules.get("IPython")
    shell = ipython.get_ipython() if ipython is not None else None
    if shell is None or not hasattr(shell, "kernel"):
        return False
    try:
        importlib.import_module("ipywidgets")
    except ImportError:
        return False
    return True


def _widget(name: str, control: Control, continuous: bool):
    import ipywidgets as w

    label = control.description or name
    style = {"description_width": "initial"}
    if isinstance(control, Toggle):
        return w.Checkbox(value=control.value, description=label, style=style)
    if isinstance(control, Choice):
        return w.Dropdown(options=list(control.options), value=control.value, description=label, style=style)
    if control.log:
        return w.FloatLogSlider(value=control.value, base=10, min=math.log10(control.min),
                                max=math.log10(control.max), step=control.step or 0.05, description=label,
                                continuous_update=continuous, style=style)
    cls = w.IntSlider if control.integer else w.FloatSlider
    step = control.step if control.step is not None else (1 if control.integer else (control.max - control.min) / 100)
    return cls(value=control.value, min=control.min, max=control.max, step=step, description=label,
               continuous_update=continuous, style=style)


def interact_or_static(fn: Callable[..., Any], controls: Mapping[str, Control], *, live: bool | None = None,
                       continuous: bool = False, columns: int = 2):
    """Bind ``fn(**values)`` to ``controls``.

    Live (``live`` None -> :func:`live_widgets`): displays a grid of widgets above an output area and
    runs ``fn`` once now and again on every change (sliders fire on release unless ``continuous``);
    returns the ``ipywidgets.interactive`` object. Static: returns ``fn(**{name: control.value})``.
    """
    if not (live_widgets() if live is None else live):
        return fn(**{name: c.value for name, c in controls.items()})
    import ipywidgets as w
    from IPython.display import display

    widgets = {name: _widget(name, c, continuous) for name, c in controls.items()}
    ui = w.interactive(fn, **widgets)
    grid = w.GridBox(list(widgets.values()), layout=w.Layout(grid_template_columns=f"repeat({columns}, 1fr)"))
    display(w.VBox([grid, ui.children[-1]]))
    return ui


# --------------------------------------------------------------------------- timing

@dataclass(frozen=True)
class Timing:
    """Wall-clock seconds of repeated calls: ``best`` (minimum), ``median``, all ``runs``."""

    best: float
    median: float
    runs: tuple[float, ...]

    def __str__(self) -> str:
        return f"best {1e3 * self.best:.1f} ms, median {1e3 * self.median:.1f} ms over {len(self.runs)} runs"


def time_call(fn: Callable[[], Any], repeat: int = 5, warmup: int = 1) -> tuple[Any, Timing]:
    """Call ``fn()`` ``warmup`` times untimed (JIT compilation), then ``repeat`` times timed
    (``time.perf_counter``); returns the last result and the :class:`Timing`."""
    if repeat < 1:
        raise ValueError("repeat must be >= 1")
    result = None
    for _ in range(warmup):
        result = fn()
    runs = []
    for _ in range(repeat):
        start = time.perf_counter()
        result = fn()
        runs.append(time.perf_counter() - start)
    return result, Timing(min(runs), statistics.median(runs), tuple(runs))


# --------------------------------------------------------------------------- preview renderer

def scaled_light_intensity(scene, factor: float):
    """``scene`` with every light's ``intensity`` multiplied by ``factor`` (>= 0)."""
    if not (factor >= 0.0 and math.isfinite(factor)):
        raise ValueError(f"scale factor must be finite and >= 0, got {factor!r}")
    return scene.replace(lights=tuple(dataclasses.replace(l, intensity=l.intensity * factor) for l in scene.lights))


def _frame_key(scene) -> tuple:
    r = scene.render
    return scene.objects, scene.camera, r.width, r.height


def _shading_key(scene) -> tuple:
    return scene.lights, scene.render.ambient, scene.render.sky_color


def _shadow_key(scene) -> tuple:
    return tuple(dataclasses.replace(l, color=(0.0, 0.0, 0.0), intensity=0.0) for l in scene.lights)


class PreviewRenderer:
    """Render scenes that differ in medium / march / post / light power while reusing the frame
    (module docstring). ``rebuilds`` counts ``frame``, ``shading`` and ``shadow_maps`` rebuilds."""

    def __init__(self) -> None:
        self._frame: Frame | None = None
        self.rebuilds = {"frame": 0, "shading": 0, "shadow_maps": 0}

    def frame(self, scene) -> Frame:
        """A frame valid for ``scene``, reusing what the previous scene built."""
        old = self._frame
        if old is None or _frame_key(old.scene) != _frame_key(scene):
            self._frame = prepare_frame(scene)
            self.rebuilds["frame"] += 1
        elif _shading_key(old.scene) != _shading_key(scene):
            keep_maps = _shadow_key(old.scene) == _shadow_key(scene)
            lights = pack_lights(scene)
            colour = scene_colour(old.gbuffer, scene, old.geometry, lights)
            self._frame = Frame(scene, old.camera, old.geometry, old.gbuffer, lights, colour,
                                old.shadow_cache if keep_maps else {})
            self.rebuilds["shading"] += 1
            self.rebuilds["shadow_maps"] += 0 if keep_maps else 1
        else:
            self._frame = dataclasses.replace(old, scene=scene)
        return self._frame

    def render(self, scene) -> dict[str, np.ndarray]:
        """The technique's buffers (``final``, ``inscatter``, ``transmittance``, stages) plus ``depth``
        and ``scene_colour`` of ``scene``, as :func:`vlref.render.render` with ``stages=True`` gives them
        (shadow maps excepted)."""
        frame = self.frame(scene)
        out = dict(TECHNIQUES[scene.render.technique].render(scene, frame))
        out.setdefault("depth", frame.gbuffer.depth)
        out.setdefault("scene_colour", frame.scene_colour)
        return out


# --------------------------------------------------------------------------- bundled example

EXAMPLE_FILES = {"reference": "reference.exr", "port_bug": "port_bug.exr", "port_fixed": "port_fixed.exr",
                 "depth": "depth.exr"}
"""Files of the port-validation example (:func:`make_port_example`)."""


def examples_dir() -> Path:
    """The folder of the bundled examples: ``$VLREF_EXAMPLES``, the source checkout's ``data/examples``,
    a ``data/examples`` above the working directory, or ``<prefix>/share/vlref/examples``."""
    env = os.environ.get("VLREF_EXAMPLES")
    candidates = [Path(env)] if env else []
    candidates.append(Path(__file__).resolve().parents[1] / "data" / "examples")
    candidates.extend(p / "data" / "examples" for p in (Path.cwd(), *Path.cwd().parents))
    candidates.append(Path(sys.prefix) / "share" / "vlref" / "examples")
    for c in candidates:
        if (c / EXAMPLE_FILES["reference"]).is_file():
            return c
    raise InputError(str(candidates[-1]), "", "bundled examples not found (looked in "
                     + ", ".join(str(c) for c in candidates) + "; set VLREF_EXAMPLES)")


def make_port_example(out_dir, scene: str = "pillars", width: int = 160, height: int = 90,
                      steps: int = 32, overrides: Sequence[str] = ()) -> dict[str, Path]:
    """Write the port-validation example of ``scene`` (``physical``, ``steps`` steps, no offsets) to ``out_dir``.

    * ``reference.exr``: the float64 render's ``final`` (float32 on disk);
    * ``port_fixed.exr``: the same render with ``render.precision = "float32"`` (a faithful port);
    * ``port_bug.exr``: the float32 render with the planted bug: ``medium.anisotropy`` negated, which is
      what a port computes when it evaluates HG at ``cos θ = dot(d, -l)`` (light vector reversed),
      because ``p(-cos θ; g) = p(cos θ; -g)``;
    * ``depth.exr``: the linear eye depth (``inf`` = sky) for ``--ignore-sky``.

    Returns the written paths by key of :data:`EXAMPLE_FILES`.
    """
    base = [f"render.width={width}", f"render.height={height}", "render.technique=\"physical\"",
            f"render.steps={steps}", "render.sampling=\"none\"", *overrides]
    ref_scene = load_scene(scene, base)
    g = ref_scene.medium.anisotropy
    runs = {"reference": base, "port_fixed": base + ["render.precision=\"float32\""],
            "port_bug": base + ["render.precision=\"float32\"", f"medium.anisotropy={-g!r}"]}
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {}
    note = {"reference": "float64 reference", "port_fixed": "float32 port",
            "port_bug": "float32 port with a planted bug: HG evaluated with the light vector reversed"}
    for key, overrides_k in runs.items():
        result = render(load_scene(scene, overrides_k))
        paths[key] = write_exr(out / EXAMPLE_FILES[key], np.asarray(result.buffers["final"], dtype=np.float32),
                               metadata={"scene": scene, "settings": " ".join(overrides_k), "note": note[key]})
        if key == "reference":
            paths["depth"] = write_exr(out / EXAMPLE_FILES["depth"], result.buffers["depth"].astype(np.float32),
                                       metadata={"scene": scene, "note": "linear eye depth, inf = sky"})
    return paths


if __name__ == "__main__":  # python -m vlref.notebook [OUT_DIR]: regenerate the bundled example
    target = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "data" / "examples"
    for name, path in make_port_example(target).items():
        print(f"{name:<11s} {path} ({path.stat().st_size} bytes)")
