"""Ground truth: the single-scattering integral solved to a stated accuracy, closed forms, technique bias.

    closed_forms.py  analytic / 1D-quadrature solutions of simple configurations (tests, docs)
    integrand.py     the exact integrand f(t) (lights, exact visibility, exact optical depths)
    quadrature.py    per-pixel adaptive G7-K15 with split points and shadow-boundary search; a frame prepared
                     once for several calls (prepare_reference)
    bias.py          a technique's error against the reference, its concentration and convergence
"""

from .bias import BiasReport, technique_bias
from .quadrature import DEFAULT_ABS_TOL, ReferenceFrame, ReferenceResult, prepare_reference, render_reference

__all__ = ["BiasReport", "technique_bias", "DEFAULT_ABS_TOL", "ReferenceFrame", "ReferenceResult", "prepare_reference",
           "render_reference"]
