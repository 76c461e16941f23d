"""The oracle: image comparison for GPU ports and the golden suite.

* :mod:`.metrics`  error metrics (max/mean abs, RMSE, relative L2, PSNR, threshold fractions, HDR-FLIP)
* :mod:`.presets`  tolerance presets (``vlref/data/presets.toml``) and the pass/fail rule's knobs
* :mod:`.compare`  masks, :func:`compare_arrays`, :func:`compare_files` (``vlref compare``: :mod:`vlref.cli.compare`)
* :mod:`.report`   report.json, diff.exr, heatmap.png, flip.png and the self-contained report.html
* :mod:`.golden`   the golden suite: build, verify, list (``vlref golden``: :mod:`vlref.cli.golden`)
* :mod:`.junit`    JUnit XML of any list of outcomes (``--junit`` of compare, golden verify, verdict)
"""

from .compare import Report, compare_arrays, compare_files
from .presets import Tolerance, load_presets, tolerance

__all__ = ["Report", "Tolerance", "compare_arrays", "compare_files", "load_presets", "tolerance"]
