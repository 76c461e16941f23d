"""``vlref march export SCENE -o DIR``: vlref's own buffers in a port's encodings (:func:`vlref.port.export_port`)."""

from __future__ import annotations

import argparse
import sys

from ..io.output_folders import check_output_dir
from ..port import export_port

HELP = None  # listed under ``vlref march``


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vlref march export", description="Export vlref's depth buffer, scene colour "
                                "and shadow maps in a port's encodings, with port.toml (docs/PORTING.md).")
    p.add_argument("scene", help="scene file or bundled scene name")
    p.add_argument("-o", "--output", required=True, help="output folder (required, no default)")
    p.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE",
                   help="override a scene field (repeatable; default: none)")
    p.add_argument("--depth", default="raw:reversed", choices=["linear", "raw:d3d", "raw:gl", "raw:reversed"],
                   help="camera depth encoding (default raw:reversed)")
    p.add_argument("--shadow", default="depth:reversed",
                   choices=["distance", "depth:linear", "depth:d3d", "depth:gl", "depth:reversed"],
                   help="shadow map encoding (default depth:reversed)")
    p.add_argument("--uv-origin", default="top", choices=["top", "bottom"],
                   help="row 0 of the exported images: top or bottom (default top)")
    p.add_argument("--camera-forward", default="+z", choices=["+z", "-z"],
                   help="view-space axis the camera looks along (default +z)")
    p.add_argument("--passes", action="store_true", help="also write vlref's pass outputs and final frame as a "
                   "port's, declared in port.toml ([[passes]], final): vlref as a port of itself, for vlref verdict "
                   "(default: off)")
    return p


def run(args) -> int:
    depth_enc, _, depth_conv = args.depth.partition(":")
    shadow_enc, _, shadow_conv = args.shadow.partition(":")
    check_output_dir(args.output)
    path = export_port(args.scene, args.output, args.set, depth_encoding=depth_enc,
                       depth_convention=depth_conv or "d3d", uv_origin=args.uv_origin,
                       shadow_encoding=shadow_enc, shadow_convention=shadow_conv or "d3d",
                       camera_forward=args.camera_forward, passes=args.passes)
    print(f"wrote {path}", file=sys.stderr)
    return 0
