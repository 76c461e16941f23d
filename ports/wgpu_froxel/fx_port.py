"""The froxel technique (Wronski 2014, Hillaire 2015) as a WebGPU port: WGSL compute shaders driven by wgpu-py.

Written from docs/TECHNIQUES.md (``froxel``), docs/CONVENTIONS.md and docs/PORTING.md §5 as an outside team
would. The raster passes (reversed-Z depth, spot and cube shadow maps, the cascaded maps of directional
lights, deferred scene colour lit by every light) are the killzone port's (``ports/wgpu/kz_port.py``, imported
as it is), and so are its light structs and map lookups (``lights.wgsl``, ``cascade_lookup.wgsl``, prepended to
the injection shader); the froxel passes are compute dispatches on 3-D textures:

====  ===========  =========================================================  ==========================
 #    pass         what                                                       target
====  ===========  =========================================================  ==========================
 0    slices       boundaries z_k, blend of exponential and uniform (host)     storage buffer (float32)
 1    inject       (S, sigma_t) per froxel at its Halton-jittered sample       rgba16float 3-D (storage)
 2    temporal     reproject the centre, reject, sample history, clamp, blend  rgba16float 3-D x2
 3    integrate    front to back per column, (L, T) at far boundaries          rgba16float 3-D
 4    apply        hardware trilinear (linear sampler, clamp) by pixel depth   rgba16float 2-D x2
 5    tile_depth   farthest eye depth per column's 3x3 tiles (next frame)      storage buffer
====  ===========  =========================================================  ==========================

Workgroups are 8x8x1; every dispatch is ``ceil(size / 8)`` groups and the shaders return outside the grid.
Temporal state (history, frame counts, tile depth, view-projection, boundaries) is carried from frame to
frame in ping-pong resources. :meth:`FroxelPort.run` runs a whole sequence for one variant
(:mod:`fx_variants`) on the raster buffers of every frame, rendered once.

Usage: ``python ports/wgpu_froxel/fx_port.py SCENE -o DIR [--frames 4] [--size 160x90] [--set K=V]``
writes ``DIR/frame_NNNN/`` per frame in the port format of docs/PORTING.md (``port.toml`` + ``.npy``).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
KZ = HERE.parent / "wgpu"
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(KZ))

import kz_port  # noqa: E402
import kz_scene  # noqa: E402
from fx_variants import VARIANTS  # noqa: E402

SHADERS = HERE / "shaders"
GROUP = 8
PASSES = (("froxel_slices", "float32"), ("froxel_scatter", "gpu-full"), ("froxel_history", "gpu-sampled"),
          ("froxel_history_frames", "gpu-full"), ("froxel_history_valid", "gpu-full"),
          ("froxel_integrated", "gpu-full"), ("inscatter", "gpu-sampled"), ("transmittance", "gpu-sampled"),
          ("final", "gpu-sampled"))
"""(buffer, preset): the exported passes, each declared in the manifest's ``[[passes]]`` under vlref's stage
name. The slice boundaries are float32 host values: ``float32``. The grids are rgba16float, one fp16 rounding
per store: ``gpu-full``, but for what the port reads through the hardware trilinear sampler, whose sub-texel
weights are 8-bit fractions on real GPUs (up to 1/512 of the difference between neighbouring texels, which
across a shadow shaft or along depth can be as large as the value itself): the history (fetched at the
reprojected position) and the apply outputs take ``gpu-sampled``: ``gpu-half`` per texel (it states that it
absorbs 8-bit filtering weights) plus a bounded share of texels, since vlref builds no geometric zone for 3-D
grids. Measured on an H100 (README): with a moving camera and sharp shafts the history fails ``gpu-full``
(35 of 3840 froxels, 1.8x) and the apply outputs do (1.4x); the frame counts, fetched the same way but nearly
constant, stay within ``gpu-full``."""


def device():
    """A wgpu device on the first adapter, with ``timestamp-query`` (per-pass GPU times) when it has it."""
    adapter, _ = kz_port.device()
    features = [f for f in ("float32-blendable", "timestamp-query") if f in adapter.features]
    return adapter, adapter.request_device_sync(required_features=features)


def shader_source(name: str) -> str:
    """A pass's WGSL: froxel_common, for injection the killzone port's lights.wgsl and cascade_lookup.wgsl
    (the light struct, incidence and map lookups both ports share), then the pass."""
    parts = [(SHADERS / "froxel_common.wgsl").read_text()]
    if name == "inject":
        parts += [(KZ / "shaders" / f"{inc}.wgsl").read_text() for inc in ("lights", "cascade_lookup")]
    return "\n".join(parts + [(SHADERS / f"{name}.wgsl").read_text()])


# --------------------------------------------------------------------------- host-side definitions (TECHNIQUES.md)

def slice_bounds(near: float, far: float, slices: int, lam: float) -> np.ndarray:
    """``z_k = λ n (f/n)^{k/D} + (1 - λ)(n + (f - n) k/D)``, then ``z_0 = 0`` and ``z_D = f`` (float64)."""
    i = np.arange(slices + 1) / slices
    z = lam * near * (far / near) ** i + (1.0 - lam) * (near + (far - near) * i)
    z[0], z[-1] = 0.0, far
    return z


def radical_inverse(index: int, base: int) -> float:
    """Halton: the digits of ``index`` in ``base`` mirrored about the point."""
    f, r = 1.0, 0.0
    while index > 0:
        f /= base
        r += f * (index % base)
        index //= base
    return r


def jitter(frame: int, mode: str, period: int) -> tuple[float, float, float]:
    """Sample offset inside every froxel: the centre, or Halton (2, 3, 5) at index ``frame mod period + 1``."""
    if mode == "none":
        return 0.5, 0.5, 0.5
    return tuple(radical_inverse(frame % period + 1, b) for b in (2, 3, 5))


def light_blocks(scene, layers) -> np.ndarray:
    """The ``Light`` array of lights.wgsl (:func:`kz_scene.light_block`, ``layers`` the raster's first layer or
    cascade per light) with ``shadow.w`` carrying the filter (0 hard, 1 pcf)."""
    out = []
    for light, layer in zip(scene.lights, layers):
        b = kz_scene.light_block(light, layer)
        b[31] = 1.0 if light.shadows and light.shadows.filter == "pcf" else 0.0
        out.append(b)
    return np.concatenate(out)


class Raster(kz_port.KillzonePort):
    """The killzone port's raster passes (depth, spot and cube shadow maps, the cascades of directional lights,
    scene colour) for a froxel scene: what the froxel port implements is checked instead of the killzone's, and
    the raster switches are a froxel variant's (:data:`fx_variants.VARIANTS`, ``raster``)."""

    @staticmethod
    def raster_switches(variant: str) -> dict:
        return VARIANTS[variant].raster

    @staticmethod
    def _check_scene(scene):
        m = scene.medium
        problems = [k for k, bad in (("medium.height_fog", m.height_fog), ("medium.noise", m.noise),
                                     ("medium.bounds", m.bounds)) if bad is not None]
        problems += [f"lights.{i}.cookie" for i, li in enumerate(scene.lights) if li.cookie is not None]
        problems += [f"lights.{i}.shadows.filter (exact)" for i, li in enumerate(scene.lights)
                     if li.shadows and li.shadows.filter == "exact"]
        if problems:
            raise ValueError("the froxel port does not implement: " + ", ".join(problems))


@dataclasses.dataclass
class FrameSetup:
    """One frame's scene (animation evaluated), raster buffers and host-side constants."""

    frame: int
    scene: object
    raster: Raster
    near_far: tuple         # the grid's near plane and far depth (metres)


class FroxelPort:
    """A sequence of frames of one scene on one device: raster passes at construction (with the raster switches
    of ``raster_variant``), froxel passes per variant (:meth:`run`)."""

    def __init__(self, scene, frames, dev=None, raster_variant: str = "faithful"):
        import wgpu
        from vlref.scene.animation import scene_at

        self.wgpu = wgpu
        self.adapter, self.device = dev if dev is not None else device()
        self.base = scene
        p = scene.techniques.froxel
        if scene.render.technique != "froxel":
            raise ValueError("the froxel port renders render.technique = 'froxel'")
        self.params = p
        self.gw, self.gh, self.d = p.grid_width, p.grid_height, p.slices
        self.timestamps = "timestamp-query" in self.device.features
        self.timings: dict[str, float] = {}        # per pass: GPU timestamps (ns ticks) if available, else wall
        self.wall_timings: dict[str, float] = {}   # per pass: CPU wall time around submit + wait
        self.frame_timings: list[tuple[dict, dict]] = []   # of the last run: (timings, wall_timings) per frame
        self.setups = []
        for f in frames:
            s = scene_at(scene.replace(render=dataclasses.replace(scene.render, frame=int(f))))
            raster = Raster(s, (self.adapter, self.device), raster_variant)
            if VARIANTS[raster_variant].stale_raster_camera and self.setups:   # the planted bug: G-buffer and
                raster.globals = raster.globals_buffer(self.setups[0].raster.cam)  # lighting keep frame 0's camera
                raster.render_scene()
            cam = raster.cam
            far = max(min(s.render.max_distance, cam.far), cam.near * (1.0 + 1e-6))
            self.setups.append(FrameSetup(int(f), s, raster, (cam.near, far)))
        usage = wgpu.TextureUsage
        self.grid_usage = usage.STORAGE_BINDING | usage.TEXTURE_BINDING | usage.COPY_SRC
        self.sampler = self.device.create_sampler(mag_filter="linear", min_filter="linear",
                                                  mipmap_filter="nearest", address_mode_u="clamp-to-edge",
                                                  address_mode_v="clamp-to-edge", address_mode_w="clamp-to-edge")
        self._pipelines: dict = {}
        if self.timestamps:
            self._queries = self.device.create_query_set(type="timestamp", count=2)
            self._resolved = self.device.create_buffer(size=16, usage=wgpu.BufferUsage.QUERY_RESOLVE
                                                       | wgpu.BufferUsage.COPY_SRC)

    # ----------------------------------------------------------------------------------- helpers

    def _buffer(self, array, usage):
        data = np.ascontiguousarray(array, dtype=np.float32)
        return self.device.create_buffer_with_data(data=data.tobytes(), usage=usage)

    def _pipeline(self, name: str, overrides: dict):
        key = (name, tuple(sorted(overrides.items())))
        if key not in self._pipelines:
            source = shader_source(name)
            consts = kz_port._constants(source, overrides)
            module = self.device.create_shader_module(code=source)
            self._pipelines[key] = self.device.create_compute_pipeline(
                layout="auto", compute={"module": module, "entry_point": "main", "constants": consts})
        return self._pipelines[key]

    def _grid(self, size=None):
        return self.device.create_texture(size=size or (self.gw, self.gh, self.d), dimension="3d",
                                          format="rgba16float", usage=self.grid_usage)

    def _dispatch(self, name, pipeline, resources: dict, groups):
        """One compute pass in its own submission: GPU time from timestamps when the adapter has them, else the
        CPU wall time around submit + wait, summed into ``timings``; the wall time also into ``wall_timings``.
        Timestamps are read as nanoseconds (wgpu-py exposes no timestamp period; NVIDIA's Vulkan period is 1 ns)."""
        entries = [{"binding": b, "resource": r} for b, r in resources.items()]
        bind = self.device.create_bind_group(layout=pipeline.get_bind_group_layout(0), entries=entries)
        enc = self.device.create_command_encoder()
        ts = {"query_set": self._queries, "beginning_of_pass_write_index": 0,
              "end_of_pass_write_index": 1} if self.timestamps else None
        cp = enc.begin_compute_pass(timestamp_writes=ts)
        cp.set_pipeline(pipeline)
        cp.set_bind_group(0, bind)
        cp.dispatch_workgroups(*groups)
        cp.end()
        if self.timestamps:
            enc.resolve_query_set(self._queries, 0, 2, self._resolved, 0)
        start = time.perf_counter()
        self.device.queue.submit([enc.finish()])
        if self.timestamps:   # read_buffer waits for the queue (wgpu-py 0.32's work-done callback is broken)
            t0, t1 = np.frombuffer(bytes(self.device.queue.read_buffer(self._resolved)), dtype=np.uint64)
        else:
            self.device.queue.read_buffer(self.setups[0].raster._fence)
        wall = time.perf_counter() - start
        seconds = float(t1 - t0) * 1e-9 if self.timestamps else wall
        self.timings[name] = self.timings.get(name, 0.0) + seconds
        self.wall_timings[name] = self.wall_timings.get(name, 0.0) + wall

    def _groups(self, n: int, partial: bool) -> int:
        return n // GROUP if partial else -(-n // GROUP)

    def read_grid(self, texture) -> np.ndarray:
        """A 3-D rgba16float texture as the stacked-slice image ``(D·gh, gw, 4)`` (PORTING §5), float32."""
        w, h, d = texture.size
        data = self.device.queue.read_texture({"texture": texture, "mip_level": 0, "origin": (0, 0, 0)},
                                              {"offset": 0, "bytes_per_row": w * 8, "rows_per_image": h}, (w, h, d))
        return np.frombuffer(bytes(data), dtype=np.float16).astype(np.float32).reshape(d * h, w, 4)

    # ----------------------------------------------------------------------------------- the sequence

    def run(self, variant: str = "faithful") -> list[dict[str, np.ndarray]]:
        """Every frame's froxel passes under ``variant``; per frame the exported buffers (float32, row 0 on top):
        ``froxel_slices`` (1, D+1), ``froxel_scatter``, ``froxel_history`` (D·gh, gw, 4),
        ``froxel_history_frames``, ``froxel_history_valid`` (D·gh, gw), ``froxel_integrated`` (D·gh, gw, 4),
        ``inscatter`` (H, W, 3), ``transmittance`` (H, W), ``final`` (H, W, 3)."""
        wgpu, d = self.wgpu, self.device
        spec = VARIANTS[variant]
        ov, p = spec.overrides, self.params
        gx, gy = self._groups(self.gw, spec.partial_groups), self._groups(self.gh, spec.partial_groups)
        storage, uniform = wgpu.BufferUsage.STORAGE, wgpu.BufferUsage.UNIFORM
        hist = [self._grid(), self._grid()]
        count = [self._grid(), self._grid()]
        tiles = [d.create_buffer(size=4 * self.gw * self.gh, usage=storage) for _ in range(2)]
        prev = None        # (view_proj, bounds) of the previous frame
        out = []
        self.frame_timings = []
        for i, fs in enumerate(self.setups):
            before, wall_before = dict(self.timings), dict(self.wall_timings)
            r, cam = fs.raster, fs.raster.cam
            lam = spec.depth_distribution if spec.depth_distribution is not None else p.depth_distribution
            bounds = slice_bounds(*fs.near_far, self.d, lam)
            xi = jitter(0 if spec.frozen_jitter else fs.frame, p.jitter, p.jitter_period)
            vp = cam.projection @ cam.view
            prev_vp, prev_bounds = prev if prev is not None else (vp, bounds)
            slices = self._buffer(np.concatenate([bounds, prev_bounds]), storage)
            m = fs.scene.medium
            block = np.concatenate([vp.T.reshape(-1), prev_vp.T.reshape(-1), [*cam.eye, 0], [*cam.frame[:, 0], 0],
                                    [*cam.frame[:, 1], 0], [*cam.frame[:, 2], 0],
                                    [math.tan(math.radians(cam.fov) / 2), cam.width / cam.height, cam.near, cam.far],
                                    [self.gw, self.gh, self.d, fs.frame], [*xi, p.history_alpha],
                                    [m.scattering, m.extinction, m.anisotropy, float(p.light_extinction)],
                                    [cam.width, cam.height, len(fs.scene.lights), math.ceil(1.0 / p.history_alpha)],
                                    [self.gw, self.gh, self.d, self.d + 1],
                                    [float(p.history_clamp), float(prev is not None), 0, 0]])
            fx = {"buffer": self._buffer(block, uniform), "offset": 0, "size": block.size * 4}
            sl = {"buffer": slices, "offset": 0, "size": slices.size}
            lights = self._buffer(light_blocks(fs.scene, r.layers), storage)
            scatter, integrated = self._grid(), self._grid()
            self._dispatch("inject", self._pipeline("inject", ov), {
                0: fx, 1: sl, 2: {"buffer": lights, "offset": 0, "size": lights.size},
                3: r.shadow.create_view(dimension="2d-array"), 4: scatter.create_view(),
                5: r.cascade_tex.create_view(dimension="2d-array"),
                6: {"buffer": r.cascade_info, "offset": 0, "size": r.cascade_info.size}}, (gx, gy, self.d))
            lit = scatter
            if p.temporal:
                cur, old = i % 2, (i + 1) % 2
                self._dispatch("temporal", self._pipeline("temporal", ov), {
                    0: fx, 1: sl, 2: scatter.create_view(), 3: hist[old].create_view(), 4: count[old].create_view(),
                    5: {"buffer": tiles[old], "offset": 0, "size": tiles[old].size}, 6: self.sampler,
                    7: hist[cur].create_view(), 8: count[cur].create_view()}, (gx, gy, self.d))
                lit = hist[cur]
                self._dispatch("tile_depth", self._pipeline("tile_depth", ov), {
                    0: fx, 2: r.depth.create_view(), 3: {"buffer": tiles[cur], "offset": 0, "size": tiles[cur].size}},
                    (gx, gy, 1))
            self._dispatch("integrate", self._pipeline("integrate", ov), {
                0: fx, 1: sl, 2: lit.create_view(), 3: integrated.create_view()}, (gx, gy, 1))
            W, H = cam.width, cam.height
            final, inscatter = [d.create_texture(size=(W, H, 1), format="rgba16float", usage=self.grid_usage)
                                for _ in range(2)]
            self._dispatch("apply", self._pipeline("apply", ov), {
                0: fx, 1: sl, 2: r.depth.create_view(), 3: integrated.create_view(), 4: self.sampler,
                5: r.colour.create_view(), 6: final.create_view(), 7: inscatter.create_view()},
                (self._groups(W, spec.partial_groups), self._groups(H, spec.partial_groups), 1))
            buffers = {"froxel_slices": bounds.astype(np.float32)[None, :], "froxel_scatter": self.read_grid(scatter),
                       "froxel_integrated": self.read_grid(integrated)}
            if p.temporal:
                counts = self.read_grid(count[i % 2])
                buffers.update({"froxel_history": self.read_grid(hist[i % 2]), "froxel_history_frames": counts[..., 0],
                                "froxel_history_valid": counts[..., 1]})
            lt = r.read(inscatter)
            buffers.update({"inscatter": lt[..., :3], "transmittance": lt[..., 3], "final": r.read(final)[..., :3]})
            out.append(buffers)
            prev = (vp, bounds)
            self.frame_timings.append(({k: v - before.get(k, 0.0) for k, v in self.timings.items()},
                                       {k: v - wall_before.get(k, 0.0) for k, v in self.wall_timings.items()}))
        return out


# --------------------------------------------------------------------------- export (docs/PORTING.md §5)

def export(port: FroxelPort, out_dir, scene_ref: str, overrides=(), frames_out=None) -> list[Path]:
    """Per frame ``out_dir/frame_NNNN/``: the raster buffers and ``port.toml`` (:func:`kz_port.export`, with
    ``render.frame=F`` in its ``set``) and, given ``frames_out`` (:meth:`FroxelPort.run`), every pass as
    ``port_<buffer>.npy``, declared with its preset in ``[[passes]]`` (:data:`PASSES`) and ``final`` (what
    ``vlref verdict`` reads); the manifests' paths."""
    paths = []
    for fs, passes in zip(port.setups, frames_out or [{}] * len(port.setups)):
        path = kz_port.export(fs.raster, Path(out_dir) / f"frame_{fs.frame:04d}", scene_ref,
                              [*overrides, f"render.frame={fs.frame}"])
        text = path.read_text()
        if "final" in passes:
            top = 'colour = "colour.npy"\n'
            text = text.replace(top, top + 'final = "port_final.npy"\n', 1)
        for name, preset in PASSES:
            if name in passes:
                np.save(path.parent / f"port_{name}.npy", np.asarray(passes[name], dtype=np.float32))
                text += f'\n[[passes]]\nname = "{name}"\nbuffer = "{name}"\npath = "port_{name}.npy"\npreset = "{preset}"\n'
        path.write_text(text)
        paths.append(path)
    return paths


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Render frames of a scene with the WebGPU froxel port and export "
                                 "every pass (docs/PORTING.md §5).")
    ap.add_argument("scene", help="vlref scene file or bundled name (technique froxel)")
    ap.add_argument("-o", "--output", required=True, help="output folder")
    ap.add_argument("--frames", type=int, default=4, help="frames 0 .. N-1 (default 4)")
    ap.add_argument("--size", default=None, help="WxH (default: the scene's render size)")
    ap.add_argument("--variant", default="faithful", choices=sorted(VARIANTS))
    ap.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE")
    args = ap.parse_args(argv)
    overrides = list(args.set)
    if args.size:
        w, h = args.size.lower().split("x")
        overrides += [f"render.width={int(w)}", f"render.height={int(h)}"]
    start = time.perf_counter()
    port = FroxelPort(kz_scene.load(args.scene, overrides), range(args.frames))
    ref = args.scene if Path(args.scene).suffix != ".toml" else str(Path(args.scene).resolve())
    paths = export(port, args.output, ref, overrides, port.run(args.variant))
    print(f"wrote {len(paths)} frames to {args.output} ({port.adapter.info['device']}, "
          f"{time.perf_counter() - start:.2f} s)")
    for name, t in port.timings.items():
        print(f"  {name:<11s} {1e3 * t / len(paths):9.2f} ms per frame")
    return 0


if __name__ == "__main__":
    sys.exit(main())
