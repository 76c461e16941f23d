"""A GPU port's own buffers in vlref: ``vlref march PORT.toml -o OUT`` and ``vlref march export``.

A port (a GPU implementation in an engine) exports its camera depth buffer, its shadow maps and the
matrices it used; vlref decodes them, builds a :class:`vlref.render.Frame` whose G-buffer depth and
shadow maps are the port's, and runs the scene's technique (march and post passes) on it. Comparing the
result with the port's own output (``vlref compare``) then isolates the port's volumetric passes from
its rasteriser and shadow renderer. ``docs/PORTING.md`` documents every key with a worked example.

Manifest (TOML; paths relative to it)::

    scene = "scene.toml"            # medium, lights, technique params: a vlref scene file or bundled name
    set = ["render.steps=16"]       # optional --set overrides of the scene (render size = the depth's)
    colour = "colour.exr"           # optional (H, W, 3) lit scene colour; default black
    shadows = true                  # false: the port renders no shadows (no map needed for shadowed lights)
    final = "final.npy"             # vlref verdict: the port's (H, W, 3) final frame
    preset = "gpu-half"             # vlref verdict: default preset of the [[passes]]
    [camera]                        # optional: default the scene's camera
    view = [[...4 rows...]]         # world -> view, column vectors
    projection = [[...]]            # view -> clip
    forward = "+z"                  # "+z" (vlref, D3D-style LH view) or "-z" (GL / Unity worldToCameraMatrix)
    convention = "d3d"              # depth convention of `projection`: d3d, gl, reversed
    [depth]
    path = "depth.exr"
    encoding = "raw"                # "linear" (eye depth, metres) or "raw" (device depth)
    convention = "reversed"         # raw: d3d ([0,1], 0 at near), gl (NDC [-1,1]), reversed (1 at near)
    near = 0.1                      # raw: the clip planes (default: the camera's)
    far = 1000.0
    uv_origin = "top"               # row 0 of the file is the top ("top") or bottom ("bottom") of the image
    [[shadow_maps]]
    light = 0                       # index of the scene light
    path = "shadow.exr"             # one file holding every tile (atlas), or
    atlas = [1, 1]                  # [columns, rows] of tiles, filled row-major from the file's first row
    encoding = "depth"              # "depth" (per `convention`) or "distance" (from the light / map plane)
    convention = "reversed"         # depth: d3d, gl, reversed (raw device depth) or linear (view depth)
    uv_origin = "top"               # row order inside each tile
    splits = [0.1, 8.0, 30.0]       # directional only: cascade split depths (N + 1 values)
    [[shadow_maps.tiles]]           # one per spot map / cube face / cascade, in atlas order
    face = "px"                     # point only: px, nx, py, ny, pz, nz (any order, each once)
    view = [[...]]
    projection = [[...]]
    [[passes]]                      # vlref verdict: one per pass output of the port
    name = "march"                  # the port's name
    buffer = "march_half"           # the vlref --stages buffer it reproduces
    path = "port_march.npy"
    preset = "gpu-half"             # optional
    ignore_sky = false              # compare only where vlref's buffer is finite

Decoding (float64):

* camera depth: ``raw`` -> :func:`vlref.camera.raw_to_linear`; the far-plane value (d3d/gl ``1``,
  reversed ``0``) exactly, or a non-finite linear depth, is sky (``inf``).
* shadow texel -> world point ``P``: ``depth`` with a raw convention: NDC ``(x_c, y_c, z)`` of the texel
  centre, ``P = (P·V)^-1 (x_c, y_c, z, 1)`` (so any projection, perspective or orthographic, any
  handedness, decodes through its own matrices; gl stores NDC z in [-1, 1]); ``linear``: the point of the
  texel's ray at view depth ``|z| = value``; ``distance``: the point at that distance along the texel's
  ray from the eye (perspective) or from the view plane ``z = 0`` (orthographic). A texel holding the
  far-plane value (raw) or a non-finite value is empty (``inf``: lit).
* vlref's packing (:mod:`vlref.lights.shadow_pack`, :mod:`.shadows`): each vlref texel takes the port texel its centre ray
  projects into (nearest); spot/point store ``|P - light|``; cascade ``k`` stores ``(P - c_k)·forward +
  back_k`` with ``(c_k, r_k)`` the bounding sphere of the camera's frustum slice between ``splits[k]``
  and ``splits[k+1]`` (vlref's cascade selection) and ``back_k`` the distance from the tile's near plane
  to ``c_k``. When the port's maps are laid out as vlref's (spot: the light frame of
  ``look_rotation(direction)``, fov = spot_angle; cube faces: the D3D frames; cascades: vlref's spheres)
  every texel maps to itself and the conversion is exact; otherwise it is a nearest resample.
* The filter (hard / pcf) and strength are the scene's (each technique may force its own filter); maps
  carry no transparent layer. Every scene light with hard or pcf shadows needs a map (else InputError
  naming the light) unless ``shadows = false``; lights without a port map are then unshadowed.

Modules: :mod:`.decode` (depth and matrix conventions, texel -> world point), :mod:`.manifest` (reading and
checking ``port.toml``), :mod:`.shadows` (a port's maps -> vlref's packed shadow maps), :mod:`.frame` (the
frame of the port's buffers, the march, its output folder), :mod:`.export` (vlref's own buffers as a port
would write them). The command line is :mod:`vlref.cli.march`.
"""

from .decode import (CUBE_ORDER, FAR_VALUE, NEAR_VALUE, PortShadowMap, PortTile, camera_from_matrices,
                     decode_depth)
from .export import export_port, orthographic
from .frame import march, march_port, march_sequence, port_frame, save_march
from .manifest import PortBuffers, load_port
from .shadows import shadow_maps_from_port

__all__ = ["PortTile", "PortShadowMap", "PortBuffers", "load_port", "decode_depth", "camera_from_matrices",
           "shadow_maps_from_port", "port_frame", "march", "march_sequence", "march_port", "save_march", "export_port",
           "orthographic", "FAR_VALUE", "NEAR_VALUE", "CUBE_ORDER"]
