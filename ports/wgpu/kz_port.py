"""The killzone technique (thesis after Vos) as a WebGPU port: WGSL shaders driven by wgpu-py.

Passes (each a real render pass writing an engine's texture formats):

====  ==========  =========================================================  ==========================
 #    pass        what                                                       target
====  ==========  =========================================================  ==========================
 1    gbuffer     scene triangles, reversed-Z depth test (greater)           depth32float, 2x rgba16float
 2    shadow      one pass per spot map / cube face, caster-side bias        depth32float 2D-array layer
 2b   cascades    per directional light: one orthographic map per cascade     depth32float 2D-array layer
 3    lighting    deferred scene colour (hard shadow-map lookups)            rgba16float
 4    downsample  min linear eye depth per march texel                       r32float (march size)
 5    volumes     per light: volume mesh (back faces), march, additive blend rgba16float (march size)
 6    upsample    bilateral 9/16, 3/16, 1/16 / (|Δz| + ε)                    rgba16float
 7/8  blur_h/v    7-tap bilateral Gaussian                                   rgba16float
 9    composite   scene · T + L, alpha = T                                   rgba16float
====  ==========  =========================================================  ==========================

Passes 1-3 depend only on the scene; :meth:`KillzonePort.run` re-runs 4-9 for a variant
(:mod:`kz_variants`: WGSL override constants and target formats) on the same raster buffers.
:func:`export` writes the port's buffers as ``.npy`` files plus ``port.toml`` (docs/PORTING.md).

Usage: ``python ports/wgpu/kz_port.py SCENE -o DIR [--size 160x90] [--variant NAME] [--set K=V]``.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import kz_scene  # noqa: E402
from kz_variants import VARIANTS  # noqa: E402

SHADERS = HERE / "shaders"
INCLUDES = {"gbuffer": ("common",), "shadow": (), "cascade": ("shadow",),
            "lighting": ("common", "lights", "cascade_lookup"),
            "downsample": ("common",),
            "march": ("common", "lights"), "upsample": ("common",), "blur": ("common",), "composite": ("common",)}
RENDER_PASSES = ("gbuffer", "shadow", "cascades", "lighting")
POST_PASSES = ("downsample", "volumes", "upsample", "blur_h", "blur_v", "composite")
RES_FACTOR = {"full": 1, "half": 2, "quarter": 4}
PASSES = (("depth_lo", "depth_half", "gpu-float32"), ("march", "march_half", None), ("upsample", "upsample", None),
          ("blur_h", "blur_h", None), ("blur_v", "blur_v", None), ("transmittance", "transmittance", None),
          ("final", "final", None))
"""(port output, the ``vlref march --stages`` buffer it reproduces, its preset): the manifest's ``[[passes]]``.
The march runs at half resolution and the light buffers are fp16: the variant's preset (``gpu-half``; a
float32 variant: ``gpu-float32``), None here. The min-depth downsample is exact up to float32 decoding:
``gpu-float32``, sky texels (``inf`` in both) left out (``ignore_sky``)."""


BACKENDS = ("Vulkan", "Metal", "D3D12")
"""wgpu backends the port runs on. Not OpenGL: wgpu's GLSL back end cannot ``textureLoad`` a depth texture
(pipeline creation fails: "textureLoad from depth textures is not supported in GLSL"), and the port reads
its depth and shadow textures that way."""


class NoAdapter(RuntimeError):
    """No WebGPU adapter on a backend of :data:`BACKENDS` (e.g. no Vulkan driver): the port cannot run here."""


def pick_adapter(adapters):
    """The first adapter on a supported backend (:data:`BACKENDS`); :class:`NoAdapter` saying what exists."""
    for adapter in adapters:
        if adapter.info.get("backend_type") in BACKENDS:
            return adapter
    found = ", ".join(f"{a.info.get('device')} ({a.info.get('backend_type')})" for a in adapters) or "none"
    raise NoAdapter(f"no WebGPU adapter on {'/'.join(BACKENDS)} (found: {found}); the port needs the Vulkan "
                    "backend (install a Vulkan driver, e.g. Mesa's lavapipe: mesa-vulkan-drivers): wgpu's OpenGL "
                    "backend cannot textureLoad depth textures")


def device():
    """A wgpu device on the first Vulkan/Metal/D3D12 adapter (:func:`pick_adapter`), with
    ``float32-blendable`` when the adapter has it."""
    os.environ.setdefault("XDG_RUNTIME_DIR", tempfile.mkdtemp(prefix="xdg-"))
    import wgpu

    try:
        adapters = wgpu.gpu.enumerate_adapters_sync()
    except Exception as exc:  # wgpu raises RuntimeError-like errors when no backend exists
        raise NoAdapter(f"no WebGPU adapter: {exc}") from exc
    adapter = pick_adapter(sorted(adapters, key=lambda a: a.info.get("adapter_type") != "DiscreteGPU"))
    features = [f for f in ("float32-blendable",) if f in adapter.features]
    return adapter, adapter.request_device_sync(required_features=features)


def shader_source(name: str) -> str:
    """A pass's WGSL with its includes prepended (the port's ``#include``)."""
    parts = [(SHADERS / f"{inc}.wgsl").read_text() for inc in INCLUDES[name]]
    return "\n".join(parts + [(SHADERS / f"{name}.wgsl").read_text()])


def _constants(source: str, overrides: dict) -> dict:
    """The override constants of ``overrides`` that ``source`` declares (WebGPU rejects unknown keys)."""
    declared = set(re.findall(r"^override\s+(\w+)", source, re.M))
    return {k: float(v) for k, v in overrides.items() if k in declared}


class KillzonePort:
    """One scene on one device: raster passes at construction (with ``raster_variant``'s switches when that
    variant is a raster one, :mod:`kz_variants`), post passes per variant (:meth:`run`)."""

    def __init__(self, scene, dev=None, raster_variant: str = "faithful"):
        import wgpu

        self.wgpu = wgpu
        self.adapter, self.device = dev if dev is not None else device()
        self.scene = scene
        self._check_scene(scene)
        self.raster_overrides = self.raster_switches(raster_variant)
        self.cam = kz_scene.camera_setup(scene)
        W, H = self.cam.width, self.cam.height
        f = RES_FACTOR[kz_scene.resolved(scene, "resolution")]
        self.low = (W // f, H // f)
        p = scene.techniques.killzone
        self.timings: dict[str, float] = {}
        d = self.device
        self._fence = d.create_buffer(size=4, usage=wgpu.BufferUsage.COPY_SRC | wgpu.BufferUsage.COPY_DST)
        self.globals = self.globals_buffer(self.cam)
        self.layers, layer, cascade = [], 0, 0   # per light: first layer of `shadow` (first cascade: directional)
        for light in scene.lights:
            shadowed = light.shadows is not None and light.shadows.enabled
            if light.type == "directional":
                self.layers.append(cascade if shadowed else -1)
                cascade += light.shadows.cascades if shadowed else 0
            else:
                self.layers.append(layer if shadowed else -1)
                layer += {"spot": 1, "point": 6}[light.type] if shadowed else 0
        self.light_blocks = np.concatenate([kz_scene.light_block(li, la) for li, la in zip(scene.lights, self.layers)])
        self.lights = self._buffer(self.light_blocks, wgpu.BufferUsage.STORAGE)
        self.shadow_res = max([li.shadows.resolution for li, la in zip(scene.lights, self.layers)
                               if la >= 0 and li.type != "directional"] + [1])
        usage = wgpu.TextureUsage
        rt = usage.RENDER_ATTACHMENT | usage.TEXTURE_BINDING | usage.COPY_SRC
        self.depth = d.create_texture(size=(W, H, 1), format="depth32float", usage=rt)
        self.normal = d.create_texture(size=(W, H, 1), format="rgba16float", usage=rt)
        self.albedo = d.create_texture(size=(W, H, 1), format="rgba16float", usage=rt)
        self.colour = d.create_texture(size=(W, H, 1), format="rgba16float", usage=rt)
        self.shadow = d.create_texture(size=(self.shadow_res, self.shadow_res, max(layer, 1)), format="depth32float",
                                       usage=rt)
        self.rt_usage = rt
        self.render_scene()

    @staticmethod
    def raster_switches(variant: str) -> dict:
        """The WGSL override constants of passes 1-3 under ``variant`` (:mod:`kz_variants`): a raster variant's
        switches, none for the others."""
        spec = VARIANTS[variant]
        return spec.overrides if spec.raster else {}

    @staticmethod
    def _check_scene(scene):
        """What this port implements: killzone, point/spot lights without cookies (every attenuation and cone
        law, shadow strength, slope bias), a homogeneous medium; raises ValueError listing what it does not.
        (The raster passes also light surfaces with directional lights and their cascades, for the froxel
        port, ports/wgpu_froxel; the volume march has none.)"""
        m = scene.medium
        problems = [k for k, bad in (("medium.height_fog", m.height_fog), ("medium.noise", m.noise),
                                     ("medium.bounds", m.bounds)) if bad is not None]
        for i, obj in enumerate(scene.objects):
            if obj.material.opacity < 1.0:
                problems.append(f"objects.{i}.material.opacity (transparent occluders)")
            if any(obj.material.emission):
                problems.append(f"objects.{i}.material.emission")
        for i, li in enumerate(scene.lights):
            if li.type == "directional":
                problems.append(f"lights.{i}.type (directional)")
            if li.cookie is not None:
                problems.append(f"lights.{i}.cookie")
            if li.shadows is not None and li.shadows.enabled and scene.techniques.killzone.shadow_filter != "hard":
                problems.append("techniques.killzone.shadow_filter (the port looks up one texel: hard)")
        p = scene.techniques.killzone
        if scene.render.technique != "killzone":
            problems.append("render.technique (the port is killzone)")
        for name, want in (("sampling", "bayer4"), ("resolution", "half")):
            if kz_scene.resolved(scene, name) != want:
                problems.append(f"render.{name} = {kz_scene.resolved(scene, name)!r} (the port has {want!r} only)")
        for name, bad in (("light_resolutions", bool(p.light_resolutions)), ("transmittance", not p.transmittance),
                          ("blur", not p.blur), ("blur_radius", p.blur_radius != 3),
                          ("blur_depth_weight", p.blur_depth_weight != "inverse")):
            if bad:
                problems.append(f"techniques.killzone.{name} = {getattr(p, name)!r} (the port implements the "
                                "default: one resolution, view transmittance, a 7-tap inverse-depth blur)")
        if problems:
            raise ValueError("the wgpu port does not implement: " + ", ".join(problems))

    # ----------------------------------------------------------------------------------- helpers

    def globals_buffer(self, cam: kz_scene.CameraSetup):
        """The ``Globals`` uniform (common.wgsl) of the scene seen by ``cam``."""
        p = self.scene.techniques.killzone
        return self._buffer(kz_scene.globals_block(self.scene, cam, self.low, p.upsample_epsilon, p.blur_sigma),
                            self.wgpu.BufferUsage.UNIFORM)

    def _buffer(self, array: np.ndarray, usage):
        data = np.ascontiguousarray(array, dtype=np.float32)
        return self.device.create_buffer_with_data(data=data.tobytes(), usage=usage)

    def _module(self, name):
        source = shader_source(name)
        return source, self.device.create_shader_module(code=source)

    def _pipeline(self, name, vs, fs, targets, overrides=None, vertex_buffers=(), depth=None, cull="none",
                  blend=None):
        source, module = self._module(name)
        consts = _constants(source, overrides or {})
        fragment = {"module": module, "entry_point": fs, "constants": consts,
                    "targets": [{"format": t, **({"blend": blend} if blend else {})} for t in targets]}
        return self.device.create_render_pipeline(
            layout="auto",
            vertex={"module": module, "entry_point": vs, "buffers": list(vertex_buffers), "constants": consts},
            primitive={"topology": "triangle-list", "cull_mode": cull, "front_face": "ccw"},
            depth_stencil=depth, multisample=None, fragment=fragment)

    def _bind(self, pipeline, group, resources):
        entries = [{"binding": i, "resource": r} for i, r in enumerate(resources)]
        return self.device.create_bind_group(layout=pipeline.get_bind_group_layout(group), entries=entries)

    @staticmethod
    def _ubuf(buf):
        return {"buffer": buf, "offset": 0, "size": buf.size}

    def _timed(self, name, encode):
        """Encode one pass, submit it and wait: its wall time on the device (lavapipe: CPU threads)."""
        enc = self.device.create_command_encoder()
        encode(enc)
        start = time.perf_counter()
        self.device.queue.submit([enc.finish()])
        self.device.queue.read_buffer(self._fence)  # waits for the queue (wgpu-py 0.32's work-done callback is broken)
        self.timings[name] = self.timings.get(name, 0.0) + time.perf_counter() - start

    def _fullscreen(self, enc, pipeline, bind, view, size, load_clear=True):
        rp = enc.begin_render_pass(color_attachments=[{"view": view, "load_op": "clear", "store_op": "store",
                                                       "clear_value": (0, 0, 0, 0)}])
        rp.set_pipeline(pipeline)
        rp.set_bind_group(0, bind)
        rp.set_viewport(0, 0, size[0], size[1], 0, 1)
        rp.draw(3)
        rp.end()

    # ----------------------------------------------------------------------------------- passes 1-3

    def render_scene(self):
        """Passes 1-3 (run by the constructor; again to time them warm)."""
        wgpu, cam = self.wgpu, self.cam
        W, H = cam.width, cam.height
        tris = kz_scene.tessellate(self.scene, cam.eye, plane_half=2.0 * cam.far)   # covers the far plane
        vbuf = self._buffer(tris, wgpu.BufferUsage.VERTEX)
        layout = {"array_stride": 36, "step_mode": "vertex", "attributes": [
            {"format": "float32x3", "offset": 0, "shader_location": 0},
            {"format": "float32x3", "offset": 12, "shader_location": 1},
            {"format": "float32x3", "offset": 24, "shader_location": 2}]}
        ztest = {"format": "depth32float", "depth_write_enabled": True, "depth_compare": "greater"}
        ov = self.raster_overrides
        gb = self._pipeline("gbuffer", "vs_main", "fs_main", ["rgba16float", "rgba16float"], ov,
                            vertex_buffers=[layout], depth=ztest)
        gb_bind = self._bind(gb, 0, [self._ubuf(self.globals)])

        def gbuffer(enc):
            rp = enc.begin_render_pass(
                color_attachments=[{"view": t.create_view(), "load_op": "clear", "store_op": "store",
                                    "clear_value": (0, 0, 0, 0)} for t in (self.normal, self.albedo)],
                depth_stencil_attachment={"view": self.depth.create_view(), "depth_clear_value": 0.0,
                                          "depth_load_op": "clear", "depth_store_op": "store"})
            rp.set_pipeline(gb)
            rp.set_bind_group(0, gb_bind)
            rp.set_vertex_buffer(0, vbuf)
            rp.draw(len(tris))
            rp.end()

        self._timed("gbuffer", gbuffer)

        sp = self._pipeline("shadow", "vs_main", "fs_main", [], ov, vertex_buffers=[layout], depth=ztest)
        shadow_clear = 1.0 if ov.get("HOST_SHADOW_CLEAR_NEAR") else 0.0
        sp_binds, self.tiles = [], []
        for i, light in enumerate(self.scene.lights):
            if self.layers[i] < 0 or light.type == "directional":   # directional: render_cascades
                continue
            for k, (face, view, proj) in enumerate(kz_scene.shadow_tiles(light)):
                sh = light.shadows
                block = np.concatenate([(proj @ view).T.reshape(-1), view.T.reshape(-1),
                                        [sh.near, light.range, sh.bias, sh.slope_bias]])
                sp_binds.append((self.layers[i] + k, sh.resolution,
                                 self._bind(sp, 0, [self._ubuf(self._buffer(block, wgpu.BufferUsage.UNIFORM))])))
                self.tiles.append((i, face, view, proj, self.layers[i] + k, sh.resolution))

        self._timed("shadow", lambda enc: self._depth_layers(enc, self.shadow, sp, sp_binds, shadow_clear, vbuf,
                                                             len(tris)))
        self.render_cascades(tris, layout, vbuf)

        lp = self._pipeline("lighting", "vs_fullscreen", "fs_main", ["rgba16float"], ov)
        lp_bind = self._bind(lp, 0, [self._ubuf(self.globals), self._ubuf(self.lights),
                                     self.shadow.create_view(dimension="2d-array"), self.depth.create_view(),
                                     self.normal.create_view(), self.albedo.create_view(),
                                     self.cascade_tex.create_view(dimension="2d-array"), self._ubuf(self.cascade_info)])
        self._timed("lighting", lambda enc: self._fullscreen(enc, lp, lp_bind, self.colour.create_view(), (W, H)))

    def _depth_layers(self, enc, texture, pipeline, binds, clear: float, vbuf, count: int):
        """One depth-only render pass per ``(layer, resolution, bind group)`` of ``binds``: ``count`` vertices of
        ``vbuf`` into that layer of ``texture`` (cleared to ``clear``), viewport the tile's resolution."""
        for layer, res, bind in binds:
            view = texture.create_view(dimension="2d", base_array_layer=layer, array_layer_count=1)
            rp = enc.begin_render_pass(color_attachments=[], depth_stencil_attachment={
                "view": view, "depth_clear_value": clear, "depth_load_op": "clear", "depth_store_op": "store"})
            rp.set_pipeline(pipeline)
            rp.set_bind_group(0, bind)
            rp.set_viewport(0, 0, res, res, 0, 1)
            rp.set_vertex_buffer(0, vbuf)
            rp.draw(count)
            rp.end()

    def render_cascades(self, tris, layout, vbuf):
        """Pass 2b, per directional light with shadows: ``shadows.cascades`` orthographic reversed-Z maps
        (cascade.wgsl), one per slice of the view frustum between the split depths of ``shadows.split_lambda``
        up to ``min(shadows.distance, camera.far)``, each covering the slice's bounding sphere in the light's
        frame (``look_frame(direction)``), its view plane ``back`` before the centre so that every caster lies
        in front. Fills ``cascade_tex`` (depth32float array), ``cascade_info`` (per cascade: centre, radius;
        back, far: cascade_lookup.wgsl), ``cascade_splits`` (per light) and ``cascade_tiles`` (light, view,
        projection, layer, res)."""
        wgpu, cam, d = self.wgpu, self.cam, self.device
        verts = tris[:, :3].astype(np.float64)
        self.cascade_tiles, self.cascade_splits, info, blocks = [], {}, [], []
        res = 1
        for i, light in enumerate(self.scene.lights):
            if light.type != "directional" or self.layers[i] < 0:
                continue
            sh = light.shadows
            res = max(res, sh.resolution)
            frame = kz_scene.look_frame(light.direction)
            fwd = frame[:, 2]
            far_c = min(sh.distance, cam.far)
            splits = kz_scene.cascade_splits(cam.near, max(far_c, cam.near * (1.0 + 1e-6)), sh.cascades,
                                             sh.split_lambda)
            self.cascade_splits[i] = splits
            for k in range(sh.cascades):
                centre, radius = kz_scene.frustum_sphere(cam, splits[k], splits[k + 1])
                back = radius + max(0.0, float(((centre - verts) @ fwd).max())) + 1.0
                far = back + radius
                view = kz_scene.view_matrix(centre - back * fwd, frame)
                proj = kz_scene.orthographic_reversed(radius, far)
                info.append([*centre, radius, back, far, 0.0, 0.0])
                blocks.append((np.concatenate([(proj @ view).T.reshape(-1), view.T.reshape(-1),
                                               [0.0, far, sh.bias, sh.slope_bias]]), sh.resolution))
                self.cascade_tiles.append((i, view, proj, len(self.cascade_tiles), sh.resolution))
        self.cascade_info = self._buffer(np.asarray(info or [[0.0] * 8]), wgpu.BufferUsage.STORAGE)
        self.cascade_tex = d.create_texture(size=(res, res, max(len(blocks), 1)), format="depth32float",
                                            usage=self.rt_usage)
        if not blocks:
            return
        pipe = self._pipeline("cascade", "vs_main", "fs_ortho", [], self.raster_overrides, vertex_buffers=[layout],
                              depth={"format": "depth32float", "depth_write_enabled": True, "depth_compare": "greater"})
        binds = [(layer, r, self._bind(pipe, 0, [self._ubuf(self._buffer(b, wgpu.BufferUsage.UNIFORM))]))
                 for layer, (b, r) in enumerate(blocks)]
        self._timed("cascades", lambda enc: self._depth_layers(enc, self.cascade_tex, pipe, binds, 0.0, vbuf,
                                                               len(tris)))

    # ----------------------------------------------------------------------------------- passes 4-9

    def run(self, variant: str = "faithful") -> dict[str, np.ndarray]:
        """Run passes 4-9 with ``variant``'s switches; returns every pass's output (float32, row 0 on top)."""
        wgpu, d = self.wgpu, self.device
        spec = VARIANTS[variant]
        ov = {} if spec.raster else spec.overrides
        fmt = spec.light_format
        W, H = self.cam.width, self.cam.height
        w, h = self.low
        tex = {name: d.create_texture(size=size + (1,), format=f, usage=self.rt_usage)
               for name, size, f in (("depth_lo", (w, h), "r32float"), ("march", (w, h), fmt),
                                     ("upsample", (W, H), fmt), ("blur_h", (W, H), fmt), ("blur_v", (W, H), fmt),
                                     ("final", (W, H), spec.final_format))}
        g = self._ubuf(self.globals)
        depth_view = self.depth.create_view()

        ds = self._pipeline("downsample", "vs_fullscreen", "fs_main", ["r32float"], ov)
        ds_bind = self._bind(ds, 0, [g, depth_view])
        self._timed("downsample", lambda enc: self._fullscreen(enc, ds, ds_bind, tex["depth_lo"].create_view(), (w, h)))

        add = {"color": {"operation": "add", "src_factor": "one", "dst_factor": "one"},
               "alpha": {"operation": "add", "src_factor": "one", "dst_factor": "one"}}
        mp = self._pipeline("march", "vs_volume", "fs_march", [fmt], ov, cull="front", blend=add, vertex_buffers=[
            {"array_stride": 12, "step_mode": "vertex",
             "attributes": [{"format": "float32x3", "offset": 0, "shader_location": 0}]}])
        lights = self.lights
        if ov.get("HOST_LIGHT_COLOUR_FP16"):   # row 2 of each Light: colour * intensity, shadow strength
            blocks = self.light_blocks.reshape(-1, 8, 4).copy()
            blocks[:, 2, :3] = np.clip(blocks[:, 2, :3], -65504.0, 65504.0).astype(np.float16)
            lights = self._buffer(blocks.reshape(-1), wgpu.BufferUsage.STORAGE)
        mp_bind = self._bind(mp, 0, [g, self._ubuf(lights), self.shadow.create_view(dimension="2d-array"),
                                     tex["depth_lo"].create_view()])
        volumes = []
        for i, light in enumerate(self.scene.lights):
            if ov.get("HOST_CULL_BEHIND_CAMERA") and (np.asarray(light.position) - self.cam.eye) @ self.cam.frame[:, 2] < 0:
                continue
            mesh = kz_scene.volume_mesh(light)
            idx = self._buffer(np.array([i, 0, 0, 0], dtype=np.uint32).view(np.float32), wgpu.BufferUsage.UNIFORM)
            volumes.append((self._buffer(mesh, wgpu.BufferUsage.VERTEX), len(mesh), self._bind(mp, 1, [self._ubuf(idx)])))

        def march(enc):
            rp = enc.begin_render_pass(color_attachments=[{"view": tex["march"].create_view(), "load_op": "clear",
                                                           "store_op": "store", "clear_value": (0, 0, 0, 0)}])
            rp.set_pipeline(mp)
            rp.set_bind_group(0, mp_bind)
            rp.set_viewport(0, 0, w, h, 0, 1)
            for vbuf, n, bind in volumes:
                rp.set_bind_group(1, bind)
                rp.set_vertex_buffer(0, vbuf)
                rp.draw(n)
            rp.end()

        self._timed("volumes", march)

        up = self._pipeline("upsample", "vs_fullscreen", "fs_main", [fmt], ov)
        up_bind = self._bind(up, 0, [g, tex["march"].create_view(), tex["depth_lo"].create_view(), depth_view])
        self._timed("upsample", lambda enc: self._fullscreen(enc, up, up_bind, tex["upsample"].create_view(), (W, H)))
        src = "upsample"
        for axis, name in ((0, "blur_h"), (1, "blur_v")):
            bp = self._pipeline("blur", "vs_fullscreen", "fs_main", [fmt], {**ov, "AXIS": axis})
            bb = self._bind(bp, 0, [g, tex[src].create_view(), depth_view])
            self._timed(name, lambda enc: self._fullscreen(enc, bp, bb, tex[name].create_view(), (W, H)))
            src = name
        cp = self._pipeline("composite", "vs_fullscreen", "fs_main", [spec.final_format], ov)
        cb = self._bind(cp, 0, [g, tex["blur_v"].create_view(), self.colour.create_view(), depth_view])
        self._timed("composite", lambda enc: self._fullscreen(enc, cp, cb, tex["final"].create_view(), (W, H)))

        out = {name: self.read(t) for name, t in tex.items()}
        out["depth_lo"] = np.where(out["depth_lo"] >= kz_scene.SKY_DEPTH, np.inf, out["depth_lo"])
        for name in ("march", "upsample", "blur_h", "blur_v"):
            out[name] = out[name][..., :3]
        out["transmittance"] = out["final"][..., 3]
        out["final"] = out["final"][..., :3]
        return out

    # ----------------------------------------------------------------------------------- read-back

    def read(self, texture, layer: int = 0) -> np.ndarray:
        """One layer of a texture as float32 ``(h, w[, 4])``, row 0 = the top row (WebGPU's first row)."""
        w, h = texture.size[0], texture.size[1]
        fmt = texture.format
        bpp = {"depth32float": 4, "r32float": 4, "rgba16float": 8, "rgba32float": 16}[fmt]
        src = {"texture": texture, "mip_level": 0, "origin": (0, 0, layer)}
        if fmt == "depth32float":
            src["aspect"] = "depth-only"
        data = self.device.queue.read_texture(src, {"offset": 0, "bytes_per_row": w * bpp}, (w, h, 1))
        dtype = np.float16 if fmt == "rgba16float" else np.float32
        a = np.frombuffer(bytes(data), dtype=dtype).astype(np.float32)
        return a.reshape(h, w, -1) if bpp > 4 else a.reshape(h, w)

    def raster_buffers(self) -> dict:
        """Passes 1-3 read back: reversed-Z depth, colour (h, w, 3) and the shadow tiles (each cascade a tile
        of its light, without a face name)."""
        return {"depth": self.read(self.depth), "colour": self.read(self.colour)[..., :3],
                "tiles": [(i, face, view, proj, self.read(self.shadow, layer)[:res, :res])
                          for i, face, view, proj, layer, res in self.tiles]
                + [(i, "", view, proj, self.read(self.cascade_tex, layer)[:res, :res])
                   for i, view, proj, layer, res in self.cascade_tiles]}


# --------------------------------------------------------------------------- export (docs/PORTING.md)

def _toml(v) -> str:
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml(a) for a in v) + "]"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    return repr(float(v)) if isinstance(v, float) else str(v)


def export(port: KillzonePort, out_dir, scene_ref: str, overrides=(), passes: dict | None = None,
           preset: str = "gpu-half") -> Path:
    """Write the port's depth, colour and shadow maps (``.npy``, float32, row 0 on top) with ``port.toml``,
    and each of ``passes`` as ``port_<name>.npy``, declared in ``[[passes]]`` (:data:`PASSES`, ``preset``) with
    ``final`` for ``vlref verdict``; returns the manifest's path."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    cam = port.cam
    raster = port.raster_buffers()
    passes = passes or {}
    np.save(out / "depth.npy", raster["depth"])
    np.save(out / "colour.npy", raster["colour"])
    lines = [f"scene = {_toml(scene_ref)}", f"set = {_toml(list(overrides))}", 'colour = "colour.npy"',
             *(['final = "port_final.npy"'] if "final" in passes else []), f"preset = {_toml(preset)}", "",
             "[camera]", 'forward = "+z"', 'convention = "reversed"', f"view = {_toml(cam.view)}",
             f"projection = {_toml(cam.projection)}", "",
             "[depth]", 'path = "depth.npy"', 'encoding = "raw"', 'convention = "reversed"',
             f"near = {cam.near!r}", f"far = {cam.far!r}", 'uv_origin = "top"', ""]
    by_light: dict[int, list] = {}
    for i, face, view, proj, texels in raster["tiles"]:
        by_light.setdefault(i, []).append((face, view, proj, texels))
    for i, tiles in by_light.items():
        np.save(out / f"shadow_{i}.npy", np.concatenate([t[3] for t in tiles], axis=1))  # tiles side by side
        lines += ["[[shadow_maps]]", f"light = {i}", f'path = "shadow_{i}.npy"', f"atlas = [{len(tiles)}, 1]",
                  'encoding = "depth"', 'convention = "reversed"', 'uv_origin = "top"']
        if i in port.cascade_splits:   # cascades: their split depths (PORTING §2)
            lines.append(f"splits = {_toml(port.cascade_splits[i])}")
        lines.append("")
        for face, view, proj, _ in tiles:
            lines += ["[[shadow_maps.tiles]]"] + ([f'face = "{face}"'] if face else [])
            lines += [f"view = {_toml(view)}", f"projection = {_toml(proj)}", ""]
    for name, buffer, pass_preset in PASSES:
        if name in passes:
            lines += ["[[passes]]", f"name = {_toml(name)}", f"buffer = {_toml(buffer)}", f'path = "port_{name}.npy"']
            lines += [f"preset = {_toml(pass_preset)}", "ignore_sky = true", ""] if pass_preset else [""]
    (out / "port.toml").write_text("\n".join(lines))
    for name, a in passes.items():
        np.save(out / f"port_{name}.npy", np.asarray(a, dtype=np.float32))
    return out / "port.toml"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description="Render a scene with the WebGPU killzone port and export its buffers "
                                "(docs/PORTING.md).")
    p.add_argument("scene", help="vlref scene file or bundled name")
    p.add_argument("-o", "--output", required=True, help="output folder")
    p.add_argument("--size", default=None, help="WxH (default: the scene's render size)")
    p.add_argument("--variant", default="faithful", choices=sorted(VARIANTS))
    p.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE")
    args = p.parse_args(argv)
    overrides = list(args.set)
    if args.size:
        w, h = args.size.lower().split("x")
        overrides += [f"render.width={int(w)}", f"render.height={int(h)}"]
    scene = kz_scene.load(args.scene, overrides)
    start = time.perf_counter()
    port = KillzonePort(scene, raster_variant=args.variant)
    passes = port.run(args.variant)
    ref = args.scene if Path(args.scene).suffix != ".toml" else str(Path(args.scene).resolve())
    path = export(port, args.output, ref, overrides, passes, VARIANTS[args.variant].preset)
    total = time.perf_counter() - start
    print(f"wrote {path} ({port.adapter.info['device']}, {total:.2f} s)")
    for name, t in port.timings.items():
        print(f"  {name:<11s} {1e3 * t:9.1f} ms")
    return 0


if __name__ == "__main__":
    sys.exit(main())
