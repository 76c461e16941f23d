"""vlref: a CPU reference renderer for real-time volumetric lighting ("god rays").

The package is laid out as the pipeline it computes::

    scene/      scene model, TOML/JSON loading and validation, bundled scenes
    camera.py   view/projection matrices, pixel rays, depth conversions
    geometry/   primitives, OBJ meshes, BVH, ray casting of the G-buffer
    lights/     light models, attenuation and cone laws, cookies, shadow maps
    medium.py   density: homogeneous, height fog, noise
    march/      ray-march kernels: light-volume segments, sampling patterns, step loops
    post/       depth downsample, blur, upsample, composite, radial blur
    techniques/ one module per technique wiring the passes with its constants
    reference/  quadrature ground truth and closed forms
    oracle/     image comparison, tolerance presets, golden suite
    port/       a GPU port's own buffers: manifest, decoding, shadow import, export, the march on them
    io.py       EXR / PNG / NPY / NPZ
    cli/        the ``vlref`` command: every argument parser, one module per sub-command
    bench/      ``vlref bench``: throughput of every stage, by section
    progress.py long kernels run band by band of rows: progress reports, Ctrl-C between bands
    warmup.py   compile every kernel once (``vlref warmup``) and the march compiled ahead of a cold render
"""

__version__ = "0.1.0"
