"""The quadrature reference: the single-scattering integral of docs/PHYSICS.md solved to a stated accuracy.

Per pixel ray ``x(t) = o + t d`` (camera position, unit pixel direction), ``t ∈ [0, t1]`` with
``t1 = min(surface distance, render.max_distance)``:

    L = T(0, t1) · L_surface + ∫_0^{t1} f(t) dt,
    f(t) = T(0, t) Σ_lights σs(x) p(cos θ) V(x) T_l(x) E_l(x)        (vlref.reference.integrand)

Method
------
1. **Split points.** ``[0, t1]`` is cut at every known discontinuity of ``f`` or of its
   derivatives: the entry/exit of each light volume (range sphere, spot cone), the medium box, the
   closest approach ``tc`` of each point/spot light (the ``1/r²`` peak), and **shadow boundaries**.
   The pieces outside the medium box are left out (``σs = 0`` there, so ``f = 0``). Where the scene
   has a single point or spot light, its ``tc`` is no split point: the pieces are integrated in ``u`` of
   ``t = tc + h tan u``, in which ``f dt/du`` is smooth across the peak
   (:func:`vlref.reference.integrand.peak_substitution`, :func:`integrand`).
2. **Shadow boundaries.** For each light, the visibility ``V`` (``geometry.shadow_transmittance``,
   an exact shadow ray, RGB for tinted occluders) is sampled at ``shadow_samples + 1`` uniformly
   spaced points of the light's active interval inside the medium box (outside it ``f = 0``);
   wherever two neighbours differ the change is bisected to ``|Δt| ≤ w · max(1, t)``,
   ``w = 1e-3 rel_tol³`` (:func:`bisection_width`; 1e-12 for every ``rel_tol ≤ 1e-3``; the bracket's
   width enters the bound, step 4). *Resolution limit*: a lit or shadowed run shorter than the grid
   spacing ``(interval length) / shadow_samples`` can fall between two samples and go unsplit. It is then still integrated (``f`` evaluates ``V`` exactly at every node), but without a
   split the Gauss–Kronrod error estimate can miss it. Size the grid so that the spacing is below
   the thinnest shadow feature along a ray (default 512 samples: 2 cm on a 10 m light volume).
3. **Adaptive Gauss–Kronrod (G7–K15, or G3–K7), global.** Each piece starts as one interval; the interval
   with the largest error estimate is bisected until
   ``Σ err ≤ max(rel_tol · max_c |I_c|, abs_tol)`` (``I_c`` the running integral of channel c; the
   test is relative to the pixel's brightest channel) or ``max_intervals`` is reached. The error of
   an interval is ``max_c |K15_c − G7_c|``: the error of the *embedded G7* result. The returned
   value is the K15 sum, which for smooth integrands is orders of magnitude more accurate, so the
   estimate is conservative (tests check that the true error of closed-form scenes stays below it).
   Each interval's estimate is at least ``50 ε ∫|f|`` (QUADPACK's rounding floor). ``rule = 7``
   uses the G3–K7 pair instead (7 evaluations per interval instead of 15; the estimate is then
   ``|K7 − G3|``, the embedded G3's error, conservative in the same way: K7 is exact to degree 11,
   G3 to degree 5). At a coarse ``rel_tol`` most pixels converge on the first pass over their
   pieces, whose cost is the rule's node count: there G3–K7 halves the work; at tight tolerances
   G7–K15 needs fewer evaluations. ``rule = 3`` (G1–K3: the 3-point Gauss rule, the midpoint its embedded
   rule, 3 evaluations; the estimate ``|K3 − G1|`` the midpoint's error) is the cheapest first pass, for
   ``rel_tol`` of 1e-2 and coarser.
4. **Error bound reported.** ``error = Σ_intervals err + Σ_boundaries |Δt| · max|f|`` (the second
   term bounds the misplacement of each bisected shadow boundary). ``abs_tol`` is the floor that
   keeps near-black pixels (no light reaches them) from demanding relative accuracy of zero.

View transmittance is exact (closed form for homogeneous and height fog, nested adaptive quadrature
with noise; see :mod:`vlref.reference.integrand`). Nothing here reuses the march's step loop.
Kernels are deterministic: every pixel is computed by one thread, in a fixed order.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numba
import numpy as np
from numba import prange

from ..geometry import traversal_stack
from ..jit import njit
from ..medium import clip_to_bounds
from ..render import Frame, prepare_frame
from . import integrand as ig
from .integrand import WG, WG1, WG3, WGK, WGK3, WGK7, XGK, XGK3, XGK7
from ..parallel import borrowed, take, task_counter, workers
from ..progress import bands_for, row_bands

__all__ = ["ReferenceResult", "ReferenceFrame", "prepare_reference", "render_reference", "DEFAULT_ABS_TOL", "RULES"]

DEFAULT_ABS_TOL = 1e-9

ROUNDOFF = 50.0 * np.finfo(np.float64).eps

RULES = (15, 7, 3)
"""The Gauss–Kronrod rules of the adaptive quadrature, by their node count: 15 (G7–K15, the default), 7 (G3–K7)
and 3 (G1–K3): fewer nodes per interval for coarse tolerances (module docstring, step 3)."""

# Band sizing (vlref.progress): a pixel traces about shadow_samples + RAYS_BEYOND_GRID shadow rays per light (its
# visibility grid, then the bisections and the quadrature's nodes) with G7–K15, the nodes' share in proportion to the
# rule's nodes with the coarser rules (a fifth of it with G1–K3), ~4 µs each on one core; a band gives each thread
# about RAYS_PER_BAND of them (~0.05 s), so a small image is one or two launches, not one per row.
RAYS_BEYOND_GRID = 100
TASK_PIXELS = 8
"""Consecutive pixels per task of the kernel's threads: a thread writes its pixels' results into cache lines of its
own (eight float64 to a line) instead of sharing each line with the threads of the neighbouring pixels, and takes
from the shared counter once per eight pixels."""
RAYS_PER_BAND = 12_500


@njit(cache=True, fastmath=False, inline="always")
def integrand(u, ray, ctx, tc, h):
    """``f`` in the variable of integration (RGB): ``f(u)`` itself where ``h = 0``, else ``f(t) dt/du`` at
    ``t = tc + h tan u``, ``dt/du = h (1 + tan² u)`` (:func:`vlref.reference.integrand.peak_substitution`)."""
    if h == 0.0:
        return ig.inscatter(u, ray, ctx)
    s = math.tan(u)
    r, g, b = ig.inscatter(tc + h * s, ray, ctx)
    jac = h * (1.0 + s * s)
    return r * jac, g * jac, b * jac


@njit(cache=True, fastmath=False)
def gk(a, b, ray, ctx, rule, tc, h):
    """Kronrod integral (RGB tuple) of ``f`` on ``[a, b]`` with ``rule`` (15: G7–K15, 7: G3–K7, 3: G1–K3;
    :data:`RULES`) nodes and its error estimate ``max_c max(|K_c - G_c|, 50 ε ∫|f_c|)`` (the second term,
    QUADPACK's, covers rounding); ``[a, b]`` in the variable of :func:`integrand` (``t`` where ``h = 0``).

    The nodes are symmetric: ``xgk[i]`` (descending, ``xgk[m] = 0`` the centre), Kronrod weights ``wgk[i]``; the
    Gauss nodes are the odd ``i`` and the centre (``m`` odd for every rule: 7, 3, 1), Gauss weight ``wg[i // 2]``.
    The sums are scalars per channel (no arrays: this is the reference's innermost loop). The integrand is compiled
    in (:func:`vlref.reference.integrand.inscatter`), at one site: the nodes are one loop."""
    if rule == 7:
        xgk, wgk, wg = XGK7, WGK7, WG3
    elif rule == 3:
        xgk, wgk, wg = XGK3, WGK3, WG1
    else:
        xgk, wgk, wg = XGK, WGK, WG
    m = xgk.size - 1
    c = 0.5 * (a + b)
    half = 0.5 * (b - a)
    k0 = k1 = k2 = g0 = g1 = g2 = a0 = a1 = a2 = 0.0
    p0 = p1 = p2 = 0.0
    # one call site of the integrand (node j: the pair i = j // 2 below (even j) and above (odd j) the centre, then the
    # centre): each site is a copy of the integrand's call, or of its code where it is compiled in. The sums take the
    # symmetric pairs, then the centre (the order of the sums is part of the bits).
    for j in range(2 * m + 1):
        i = j // 2
        x = c if j == 2 * m else (c - half * xgk[i] if j % 2 == 0 else c + half * xgk[i])
        f0, f1, f2 = integrand(x, ray, ctx, tc, h)
        if j == 2 * m:
            k0 += wgk[m] * f0
            k1 += wgk[m] * f1
            k2 += wgk[m] * f2
            a0 += wgk[m] * abs(f0)
            a1 += wgk[m] * abs(f1)
            a2 += wgk[m] * abs(f2)
            g0 += wg[m // 2] * f0
            g1 += wg[m // 2] * f1
            g2 += wg[m // 2] * f2
        elif j % 2 == 0:
            p0, p1, p2 = f0, f1, f2
        else:
            s0, s1, s2 = p0 + f0, p1 + f1, p2 + f2
            k0 += wgk[i] * s0
            k1 += wgk[i] * s1
            k2 += wgk[i] * s2
            a0 += wgk[i] * (abs(p0) + abs(f0))
            a1 += wgk[i] * (abs(p1) + abs(f1))
            a2 += wgk[i] * (abs(p2) + abs(f2))
            if i % 2 == 1:
                g0 += wg[i // 2] * s0
                g1 += wg[i // 2] * s1
                g2 += wg[i // 2] * s2
    k0 *= half
    k1 *= half
    k2 *= half
    err = max(0.0, abs(k0 - g0 * half), ROUNDOFF * a0 * abs(half))
    err = max(err, abs(k1 - g1 * half), ROUNDOFF * a1 * abs(half))
    err = max(err, abs(k2 - g2 * half), ROUNDOFF * a2 * abs(half))
    return k0, k1, k2, err


@njit(cache=True, fastmath=False)
def scratch(max_intervals, max_splits):
    """The work arrays of one thread's pixels, allocated once per thread (a pixel used to allocate ~0.2 MB at the
    default ``max_intervals``, on every pixel): ``(cuts, edges, lo, hi, val, err, frozen)``, the split points
    (``max_splits``), the sorted piece edges and the intervals of :func:`adaptive` (``max(max_intervals,
    max_splits + 2)``: room for every piece)."""
    cap = max(max_intervals, max_splits + 2)
    return (np.empty(max_splits), np.empty(max_splits + 2), np.empty(cap), np.empty(cap), np.empty((cap, 3)),
            np.empty(cap), np.empty(cap, dtype=np.bool_))


@njit(cache=True, fastmath=False, inline="always")
def adaptive(edges, n_edges, ray, ctx, rel_tol, abs_tol, max_intervals, rule, tc, h, work):
    """Global adaptive Gauss–Kronrod (``rule``, :func:`gk`) over the pieces ``edges[0..n_edges-1]`` (in the
    variable of :func:`integrand`, ``tc`` and ``h``), at most ``max(max_intervals, n_edges)`` intervals, in the
    arrays of ``work`` (:func:`scratch`).

    Returns ``(integral RGB (a tuple), error estimate, intervals used, converged)``.
    """
    cap = max(max_intervals, n_edges)
    _, _, lo, hi, val, err, frozen = work
    n = 0
    for i in range(n_edges - 1):
        if edges[i + 1] > edges[i]:
            lo[n], hi[n] = edges[i], edges[i + 1]
            frozen[n] = False
            n += 1
    halved = -1  # the interval just halved (its left half), evaluated with the new intervals fresh..n-1
    fresh = 0
    while True:
        for j in range(fresh - 1 if halved >= 0 else fresh, n):  # one call site of gk
            i = halved if j < fresh else j
            val[i, 0], val[i, 1], val[i, 2], err[i] = gk(lo[i], hi[i], ray, ctx, rule, tc, h)
        t0 = t1 = t2 = 0.0
        e_sum = 0.0
        worst = -1
        for i in range(n):
            t0 += val[i, 0]
            t1 += val[i, 1]
            t2 += val[i, 2]
            e_sum += err[i]
            if not frozen[i] and (worst < 0 or err[i] > err[worst]):
                worst = i
        tol = max(rel_tol * max(abs(t0), abs(t1), abs(t2)), abs_tol)
        if e_sum <= tol:
            return (t0, t1, t2), e_sum, n, True
        if worst < 0 or n >= cap:
            return (t0, t1, t2), e_sum, n, False
        a, b = lo[worst], hi[worst]
        m = 0.5 * (a + b)
        if not (a < m < b) or (b - a) <= 1e-14 * max(1.0, abs(m)):
            frozen[worst] = True
            halved, fresh = -1, n
            continue
        hi[worst] = m
        lo[n], hi[n] = m, b
        frozen[n] = False
        halved, fresh = worst, n
        n += 1


@njit(cache=True, fastmath=False)
def _same(a, b):
    return a[0] == b[0] and a[1] == b[1] and a[2] == b[2]


@njit(cache=True, fastmath=False)
def bisection_width(rel_tol):
    """Relative width ``w`` to which a shadow boundary's bracket is bisected: ``|Δt| ≤ w max(1, t)``,
    ``w = 1e-3 rel_tol³`` above ``rel_tol = 1e-3``, 1e-12 below. The misplacement term ``|Δt| max|f|`` of the
    bound (module docstring, step 4) then stays far below ``rel_tol`` of a pixel whose lit run is longer than
    ``w t`` (1 cm at ``t = 10`` for ``rel_tol = 1``), and every ``rel_tol ≤ 1e-3`` keeps the 1e-12 of a converged
    answer (~40 shadow rays per boundary; ~10 at ``rel_tol = 1``)."""
    return 1e-3 * rel_tol * rel_tol * rel_tol if rel_tol > 1e-3 else 1e-12


@njit(cache=True, fastmath=False, inline="always")
def shadow_boundaries(light, a, b, samples, width, ray, ctx, out, n_out):
    """Append to ``out`` the visibility changes of ``light`` on ``[a, b]`` found on a uniform grid of
    ``samples`` steps and bisected to ``width max(1, t)`` (:func:`bisection_width`); returns ``(n_out, Σ |Δt|
    max|f|)`` (the remaining width of each bracket times the integrand's largest value at its ends, the
    misplacement term of the error bound)."""
    widths = 0.0
    if not b > a:
        return n_out, widths
    prev_t = a
    prev_v = ig.visibility(light, a, ray, ctx)
    for i in range(1, samples + 1):
        t = b if i == samples else a + (b - a) * i / samples
        v = ig.visibility(light, t, ray, ctx)
        if not _same(v, prev_v) and n_out < out.size:
            lo, hi, v_lo = prev_t, t, prev_v
            while hi - lo > width * max(1.0, abs(hi)):
                mid = 0.5 * (lo + hi)
                if not (lo < mid < hi):
                    break
                vm = ig.visibility(light, mid, ray, ctx)
                if _same(vm, v_lo):
                    lo = mid
                else:
                    hi = mid
            out[n_out] = 0.5 * (lo + hi)
            n_out += 1
            peak = 0.0
            for end in (lo, hi):  # one call site of the integrand
                f = ig.inscatter(end, ray, ctx)
                peak = max(peak, abs(f[0]), abs(f[1]), abs(f[2]))
            widths += (hi - lo) * peak
        prev_t, prev_v = t, v
    return n_out, widths


@njit(cache=True, fastmath=False, inline="always")
def pixel_integral(ray, t1, ctx, rel_tol, abs_tol, shadow_samples, max_intervals, rule, work):
    """Inscatter (RGB), error bound, interval count, convergence flag and number of shadow boundaries
    found, for one pixel ray on ``[0, t1]`` (``work``: the thread's :func:`scratch`)."""
    cuts, edges = work[0], work[1]
    # f = 0 outside the medium box (σs = 0 there): only its pieces inside the box are integrated, and only there are
    # shadow boundaries searched. The box's entry and exit are edges (split_points), so the pieces kept are the same.
    inside, outside = clip_to_bounds(ctx.medium.params, ray[0], ray[1], ray[2], ray[3], ray[4], ray[5], 0.0, t1)
    light, tc, h = ig.peak_substitution(ray, inside, outside, ctx.lights)
    n = ig.split_points(ray, 0.0, t1, ctx.lights, ctx.medium.params, cuts, light)
    boundary_err = 0.0
    n_geom = n
    width = bisection_width(rel_tol)
    for light in range(ig.light_count(ctx)):
        a, b = ig.light_interval(light, ray, inside, outside, ctx.lights)
        if ig.casts_shadows(light, ctx):
            n, w = shadow_boundaries(light, a, b, shadow_samples, width, ray, ctx, cuts, n)
            boundary_err += w
    edges[0] = 0.0
    m = 1
    for i in range(n):
        if 0.0 < cuts[i] < t1:
            edges[m] = cuts[i]
            m += 1
    edges[m] = t1
    m += 1
    edges[:m].sort()
    k = 0
    for i in range(m):
        if inside <= edges[i] <= outside:
            edges[k] = edges[i]
            k += 1
    if h > 0.0:  # the pieces in the variable u of t = tc + h tan u (monotone: still in order)
        for i in range(k):
            edges[i] = math.atan((edges[i] - tc) / h)
    total, err, used, ok = adaptive(edges, k, ray, ctx, rel_tol, abs_tol, max_intervals, rule, tc, h, work)
    # converged only where the whole bound, the boundaries' term included, is within the tolerance
    ok = ok and err + boundary_err <= max(rel_tol * max(abs(total[0]), abs(total[1]), abs(total[2])), abs_tol)
    return total, err + boundary_err, used, ok, n - n_geom


@njit(cache=True, fastmath=False)
def _reference_tasks(taken, origin, dirs, t_end, ctx, rel_tol, abs_tol, shadow_samples, max_intervals, max_splits,
                     rule, results):
    """Take tasks of :data:`TASK_PIXELS` consecutive pixels (row-major, :func:`vlref.parallel.take` on ``taken``)
    until none is left and solve each pixel's integral (:func:`pixel_integral`, in one :func:`scratch` for all of
    them) and view transmittance into ``results`` ``(out, trans, err, used, ok, shadow_edges)``."""
    h, w = t_end.shape
    out, trans, err, used, ok, shadow_edges = results
    start = take(taken) * TASK_PIXELS
    if start >= h * w:
        return
    # only by the threads that found a pixel: the work arrays and the shadow rays' traversal stack
    work = scratch(max_intervals, max_splits)
    ctx = ig.with_stack(ctx, traversal_stack())
    while start < h * w:
        for p in range(start, min(start + TASK_PIXELS, h * w)):
            y = p // w
            x = p - y * w
            ray = (origin[0], origin[1], origin[2], dirs[y, x, 0], dirs[y, x, 1], dirs[y, x, 2])
            total, e, n, good, nb = pixel_integral(ray, t_end[y, x], ctx, rel_tol, abs_tol, shadow_samples,
                                                   max_intervals, rule, work)
            out[y, x, 0], out[y, x, 1], out[y, x, 2] = total
            err[y, x] = e
            used[y, x] = n
            ok[y, x] = good
            shadow_edges[y, x] = nb
            trans[y, x] = math.exp(-ig.view_optical_depth(ray, 0.0, t_end[y, x], ctx))
        start = take(taken) * TASK_PIXELS


@njit(cache=True, fastmath=False, parallel=True)
def _reference_kernel(origin, dirs, t_end, geo, lights, shadows, medium, light_extinction, bounded, rel_tol, abs_tol,
                      shadow_samples, max_intervals, max_splits, rule, workers):
    """Every pixel of the band ``t_end`` (H, W): the threads of a ``prange`` over ``workers`` (one per thread,
    :func:`vlref.parallel.workers`) take tasks of pixels on demand (a pixel without shadow boundaries costs a few
    dozen integrand evaluations, one crossing several shadows hundreds: ``prange``'s static split would
    leave threads idle), with the arrays borrowed (:func:`vlref.parallel.borrowed`: no reference counts
    on the records every shadow ray reads). Which thread solves a pixel changes no bit of it."""
    h, w = t_end.shape
    out = np.zeros((h, w, 3))
    trans = np.ones((h, w))
    err = np.zeros((h, w))
    used = np.zeros((h, w), dtype=np.int64)
    ok = np.ones((h, w), dtype=np.bool_)
    shadow_edges = np.zeros((h, w), dtype=np.int64)
    taken = task_counter()
    no_stack = (np.empty(0, dtype=np.int64), np.empty(0))  # a thread that takes a pixel makes its own
    for _ in prange(workers):
        o, d, te, g, lts, shd, med, res, st = borrowed((origin, dirs, t_end, geo, lights, shadows, medium,
                                                        (out, trans, err, used, ok, shadow_edges), no_stack))
        # assembled in the loop's body (Numba's parfor cannot pass nested tuples in)
        ctx = ig.ReferenceContext(g, lts, shd, med, light_extinction, bounded, st)
        _reference_tasks(taken, o, d, te, ctx, rel_tol, abs_tol, shadow_samples, max_intervals, max_splits, rule, res)
    return out, trans, err, used, ok, shadow_edges


@dataclass
class ReferenceResult:
    """The quadrature reference of one scene.

    inscatter : (H, W, 3) in-scattered radiance ``∫ f dt``.
    transmittance : (H, W) view transmittance ``T(0, t1)``.
    final : (H, W, 3) ``T · scene_colour + inscatter`` (scene colour from ``vlref.render.prepare_frame``).
    error : (H, W) per-pixel error bound on ``inscatter`` (max over channels, see the module docstring).
    max_error : the largest entry of ``error``.
    stats : counts and timings: ``intervals`` (total Gauss–Kronrod intervals), ``unconverged`` (pixels that
        hit ``max_intervals`` or the bisection floor; their ``error`` is still an honest estimate),
        ``rel_tol``, ``abs_tol``, ``shadow_samples``, ``rule``, ``seconds`` (the whole call), ``frame_seconds`` (its
        part before the quadrature: frame, camera rays, surface distances; next to nothing where the call was given a
        :class:`ReferenceFrame`), ``frame_reused`` (it was), and ``shadow_boundaries`` (H, W) int,
        the number of visibility changes found along each pixel ray.
    """

    inscatter: np.ndarray
    transmittance: np.ndarray
    final: np.ndarray
    error: np.ndarray
    max_error: float
    stats: dict = field(default_factory=dict)


@dataclass(frozen=True)
class ReferenceFrame:
    """What the quadrature of a scene's pixels reads besides its settings, prepared once by
    :func:`prepare_reference`: :func:`render_reference` given it instead of a scene reuses it, so a sweep of
    ``rel_tol``, ``shadow_samples`` or ``rule`` over one scene (a notebook's) pays the frame once, as a renderer
    with its scene loaded does.

    frame : :class:`vlref.render.Frame` of the scene (its ``scene`` evaluated at ``render.frame``).
    rows : ``(y0, y1)``, the image rows prepared.  origin : (3,) the camera's position.
    dirs : (y1 - y0, W, 3) the unit pixel directions.  t_end : (y1 - y0, W) each ray's end, ``min(surface
    distance, render.max_distance)``.  context : :class:`~vlref.reference.integrand.ReferenceContext`.
    seconds : the time its preparation took.
    """

    frame: Frame
    rows: tuple[int, int]
    origin: np.ndarray
    dirs: np.ndarray
    t_end: np.ndarray
    context: ig.ReferenceContext
    seconds: float


def prepare_reference(scene, rows: tuple[int, int] | None = None, progress=None) -> ReferenceFrame:
    """The :class:`ReferenceFrame` of ``scene`` (rows ``y0 <= y < y1`` of ``rows``, all when None): its frame
    (:func:`vlref.render.prepare_frame`: camera, geometry, G-buffer, scene colour), the pixel rays and their ends."""
    start = time.perf_counter()
    frame = prepare_frame(scene, progress)
    scene = frame.scene  # evaluated at render.frame (animated scenes)
    cam = frame.camera
    y0, y1 = rows if rows is not None else (0, scene.render.height)
    dirs = np.ascontiguousarray(cam.ray_directions()[y0:y1])
    surface = cam.eye_depth_to_distance(frame.gbuffer.depth[y0:y1], dirs)
    return ReferenceFrame(frame, (y0, y1), np.asarray(cam.position, dtype=np.float64), dirs,
                          np.minimum(surface, scene.render.max_distance), ig.build_context(scene, frame),
                          time.perf_counter() - start)


def render_reference(scene, rel_tol: float = 1e-4, abs_tol: float = DEFAULT_ABS_TOL, progress=None,
                     shadow_samples: int = 512, max_intervals: int = 4000,
                     rows: tuple[int, int] | None = None, rule: int = 15) -> ReferenceResult:
    """Solve the single-scattering integral of every pixel of ``scene`` (see the module docstring).

    ``scene``: a scene, or a :class:`ReferenceFrame` of one (:func:`prepare_reference`), reused as it is: the same
    result, bit for bit, as the scene's (its rows; ``rows`` must then be None);
    ``rel_tol``: target error relative to the pixel's brightest inscatter channel;
    ``abs_tol``: absolute floor (radiance units, default 1e-9) for pixels with (nearly) no inscatter;
    ``progress``: optional callable receiving stage names; ``shadow_samples`` (>= 1): visibility grid
    size per light and pixel (step 2 of the module docstring: runs longer than the light's interval along the
    ray / ``shadow_samples`` are split at their boundaries, and the bound holds there); ``max_intervals``:
    adaptive budget per pixel; ``rows``: only the image
    rows ``y0 <= y < y1`` (a tile: pixels are independent, so its values equal those rows of the whole
    image bit for bit; :mod:`vlref.reference.tiles`); ``rule``: the Gauss–Kronrod rule, 15 (G7–K15), 7 (G3–K7,
    half the integrand evaluations of an interval: for coarse ``rel_tol``, where most pixels converge at the first
    pass; the reported bound is then the embedded G3's error, see docs/PHYSICS.md) or 3 (G1–K3, 3 evaluations, the
    bound the midpoint's error: for ``rel_tol`` 1e-2 and coarser) (:data:`RULES`).
    """
    if int(shadow_samples) < 1:
        raise ValueError(f"render_reference: shadow_samples must be at least 1, not {shadow_samples}")
    if rule not in RULES:
        raise ValueError(f"render_reference: rule must be one of {RULES} (Gauss–Kronrod nodes), not {rule}")
    start = time.perf_counter()
    if isinstance(scene, ReferenceFrame):
        if rows is not None:
            raise ValueError("render_reference: rows come with the ReferenceFrame (prepare_reference's rows)")
        prepared = scene
    else:
        prepared = prepare_reference(scene, rows, progress)
    frame, (y0, y1), origin, dirs, t_end, ctx = (prepared.frame, prepared.rows, prepared.origin, prepared.dirs,
                                                 prepared.t_end, prepared.context)
    max_splits = ig.max_split_points(ctx, shadow_samples)
    frame_seconds = time.perf_counter() - start
    # bands of rows (vlref.progress: a moving bar, Ctrl-C between bands), sized by their shadow rays; pixels are
    # independent
    work = t_end.size * (int(shadow_samples) + RAYS_BEYOND_GRID * int(rule) // 15) * max(1, len(frame.scene.lights))
    # ctx without its stack: each thread makes its own
    bands = [_reference_kernel(origin, dirs[b0:b1], t_end[b0:b1], *ctx[:-1], float(rel_tol), float(abs_tol),
                               int(shadow_samples), int(max_intervals), max_splits, int(rule),
                               workers(-(-t_end[b0:b1].size // TASK_PIXELS)))
             for b0, b1 in row_bands(t_end.shape[0], bands_for(work, RAYS_PER_BAND * numba.get_num_threads()))]
    inscatter, trans, err, used, ok, edges = (np.concatenate(parts) if len(parts) > 1 else parts[0]
                                              for parts in zip(*bands))
    if progress is not None:
        progress("reference")
    final = trans[..., None] * frame.scene_colour[y0:y1] + inscatter
    stats = {"intervals": int(used.sum()), "unconverged": int((~ok).sum()), "rel_tol": rel_tol,
             "abs_tol": abs_tol, "shadow_samples": shadow_samples, "rule": rule, "seconds": time.perf_counter() - start,
             "frame_seconds": frame_seconds, "frame_reused": prepared is scene,
             "shadow_boundaries": edges}
    return ReferenceResult(inscatter, trans, final, err, float(err.max(initial=0.0)), stats)
