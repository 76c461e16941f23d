"""vlref: a CPU reference renderer for real-time volumetric lighting ("god rays").

The package is laid out as the pipeline it computes::

    scene/      scene model, TOML/JSON loading and validation, bundled scenes, animation
    camera.py   view/projection matrices, pixel rays, depth conversions
    geometry/   primitives, OBJ meshes, BVH, ray casting of the G-buffer
    lights/     light models, attenuation and cone laws, cookies, shadow maps (record, casting, lookups, probes)
    medium.py   density: homogeneous, height fog, noise; optical depth; the Beer–Lambert step rules
    phase.py    the Henyey–Greenstein phase function
    march/      ray-march kernels: light-volume segments, sampling patterns, step loops
    froxel/     the froxel grid: slices, the scatter / integrate / apply kernels, temporal reprojection
    post/       depth downsample, blur, upsample, composite, radial blur
    techniques/ one module per technique wiring the passes with its constants
    render.py   orchestration: a frame (camera, G-buffer, lights, scene colour), then the technique
    sequence.py frames A..B-1 in order with temporal history; EXR sequences and previews
    reference/  quadrature ground truth and closed forms
    oracle/     image comparison, tolerance presets, golden suite
    sweep.py    ``vlref sweep``: techniques × a grid of overrides, measured against the reference
    port/       a GPU port's own buffers: manifest, decoding, shadow import, export, the march on them
    io/         files: atomic writes, all-or-nothing output folders, EXR, checked image readers, the preview
                tone map and PNG, luminance and exposure, a render's files
    tomlfile.py the one reader of vlref's TOML formats (scenes, suites, sweeps, manifests, presets)
    errors.py   InputError, the one error type for bad input (``FILE: key.path: reason``)
    numeric.py  float-type helpers (``cast``, ``zero_one``) and vectorisable ``exp`` / ``expm1``
    parallel.py tasks handed out on demand to the kernels' threads, arrays without reference counts
    work_items.py  independent work items in this process or on a Dask cluster
    memory.py   peak memory of a render, estimated before anything is allocated
    notebook.py helpers for the Jupyter notebooks (display, controls, preview re-renders)
    cli/        the ``vlref`` command: every argument parser, one module per sub-command
    bench/      ``vlref bench``: throughput of every stage, by section
    processes.py child processes that leave Ctrl-C to vlref; the cores this process may use
    progress.py long kernels run band by band of rows: progress reports, Ctrl-C between bands
    warmup.py   compile every kernel once (``vlref warmup``)
    ahead.py    a cold render's later stages compiled ahead in second processes
"""

__version__ = "0.1.0"
