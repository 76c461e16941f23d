"""Light models: attenuation and cone laws against their formulas, cookies, packing, incidence."""

import math

import imageio.v3 as iio
import numpy as np
import pytest

from vlref.lights import pack_lights
from vlref.lights.attenuation import (ATTENUATION_CODES, INVERSE_SQUARE, MIN_DISTANCE, UNITY, WINDOWED,
                                     distance_attenuation)
from vlref.lights.cone import CONE_CODES, CONE_LINEAR, CONE_SMOOTHSTEP, CONE_UNITY, cone_falloff, default_inner_angle
from vlref.lights.cookies import load_cookie, sample_texture, spot_cookie_uv
from vlref.lights.pack import F_COS_INNER, F_COS_OUTER, F_CR, F_UNITY_A, F_UNITY_B, I_ATT, I_CONE
from vlref.geometry import shadow_transmittance
from vlref.geometry.obj import write_obj
from vlref.lights.shading import SURFACE_OFFSET, light_incidence
from vlref.lights.shadow_lookup import apply_strength
from vlref.render import prepare_frame
from vlref.scene.model import (ATTENUATIONS, CONE_LAWS, Box, CameraSettings, Cookie, Cylinder, Light, Material,
                               Mesh, Plane, RenderSettings, Scene, ShadowSettings, Sphere)

NO_LUT = np.zeros((0, 0))
R = 10.0


@pytest.mark.parametrize("d", [0.001, 0.3, 1.0, 4.0, 9.99, 10.0, 12.0])
def test_attenuation_laws_match_formulas(d):
    d2, inv = d * d, 1.0 / (R * R)
    inside = d < R
    inv_sq = 1.0 / max(d2, MIN_DISTANCE ** 2)
    assert distance_attenuation(INVERSE_SQUARE, d2, inv, NO_LUT) == pytest.approx(inv_sq * inside, rel=1e-14)
    u = d2 / R ** 2
    folk = 1.0 / (1.0 + 25.0 * u) * min(max(5.0 * (1.0 - math.sqrt(u)), 0.0), 1.0)
    assert distance_attenuation(UNITY, d2, inv, NO_LUT) == pytest.approx(folk * inside, rel=1e-14, abs=1e-300)
    win = min(max(1.0 - (d / R) ** 4, 0.0), 1.0) ** 2 * inv_sq
    assert distance_attenuation(WINDOWED, d2, inv, NO_LUT) == pytest.approx(win * inside, rel=1e-12, abs=1e-300)


def test_every_distance_law_of_the_scene_model_has_its_own_code_and_curve():
    """One list: the scene model's ATTENUATIONS numbered in order; a law named there without its own branch in
    the kernels would fall through to another law's curve, and two equal curves fail here."""
    assert list(ATTENUATION_CODES) == list(ATTENUATIONS)
    assert sorted(ATTENUATION_CODES.values()) == list(range(len(ATTENUATIONS)))
    d2 = np.linspace(0.0, 1.2, 25) * R * R
    curves = {law: tuple(distance_attenuation(code, x, 1.0 / R ** 2, NO_LUT) for x in d2)
              for law, code in ATTENUATION_CODES.items()}
    assert len(set(curves.values())) == len(ATTENUATIONS)
    packed = pack_lights(Scene(lights=tuple(Light(type="point", attenuation=law) for law in ATTENUATIONS)))
    assert list(packed.ints[:, I_ATT]) == [ATTENUATION_CODES[law] for law in ATTENUATIONS]


def test_every_cone_law_of_the_scene_model_has_its_own_code_and_curve():
    assert list(CONE_CODES) == list(CONE_LAWS)
    assert sorted(CONE_CODES.values()) == list(range(len(CONE_LAWS)))
    cosines = np.cos(np.radians(np.linspace(0.0, 25.0, 26)))
    curves = {law: tuple(_cone(code, c, 40.0, 24.0) for c in cosines) for law, code in CONE_CODES.items()}
    assert len(set(curves.values())) == len(CONE_LAWS)
    packed = pack_lights(Scene(lights=tuple(Light(type="spot", cone=law) for law in CONE_LAWS)))
    assert list(packed.ints[:, I_CONE]) == [CONE_CODES[law] for law in CONE_LAWS]


def test_unity_lut_is_sampled_bilinearly_with_clamp():
    lut = np.array([[1.0, 0.5, 0.25, 0.0]])  # texel centres at u = 0.125, 0.375, 0.625, 0.875
    inv = 1.0 / R ** 2
    for u, want in [(0.05, 1.0), (0.125, 1.0), (0.25, 0.75), (0.5, 0.375), (0.8, 0.075)]:
        assert distance_attenuation(UNITY, u * R * R, inv, lut) == pytest.approx(want, abs=1e-12)


def test_attenuation_float32_stays_float32():
    f = np.float32
    out = distance_attenuation(WINDOWED, f(4.0), f(0.01), np.zeros((0, 0), np.float32))
    assert isinstance(out, float) and out == pytest.approx(0.25 * (1 - 0.0016) ** 2, rel=1e-6)


def _cone(law, cos_t, outer_deg, inner_deg):
    co, ci = math.cos(math.radians(outer_deg / 2)), math.cos(math.radians(inner_deg / 2))
    a = 1.0 / max(0.001, ci - co)
    return cone_falloff(law, cos_t, co, ci, math.radians(outer_deg / 2), math.radians(inner_deg / 2), a, -co * a)


@pytest.mark.parametrize("angle", [0.0, 5.0, 12.0, 17.0, 19.9, 20.0, 25.0, 60.0])
def test_cone_laws_match_formulas(angle):
    outer, inner = 40.0, 24.0  # full angles: half-angles 20 and 12 degrees
    c = math.cos(math.radians(angle))
    co, ci = math.cos(math.radians(20)), math.cos(math.radians(12))
    x = min(max((c - co) / (ci - co), 0.0), 1.0)
    assert _cone(CONE_SMOOTHSTEP, c, outer, inner) == pytest.approx(x * x * (3 - 2 * x), abs=1e-12)
    lin = min(max((20.0 - angle) / (20.0 - 12.0), 0.0), 1.0)
    assert _cone(CONE_LINEAR, c, outer, inner) == pytest.approx(lin, abs=1e-9)
    unity = min(max((c - co) / (ci - co), 0.0), 1.0) ** 2
    assert _cone(CONE_UNITY, c, outer, inner) == pytest.approx(unity, abs=1e-12)


def test_cone_laws_are_zero_at_and_beyond_the_outer_angle_and_step_when_inner_equals_outer():
    c_out = math.cos(math.radians(15))
    for law in (CONE_UNITY, CONE_LINEAR, CONE_SMOOTHSTEP):
        assert _cone(law, c_out, 30.0, 20.0) == 0.0
        assert _cone(law, math.cos(math.radians(16)), 30.0, 20.0) == 0.0
        assert _cone(law, 1.0, 30.0, 20.0) == 1.0
    assert _cone(CONE_SMOOTHSTEP, math.cos(math.radians(14.9)), 30.0, 30.0) == 1.0
    assert _cone(CONE_LINEAR, math.cos(math.radians(14.9)), 30.0, 30.0) == 1.0


def test_default_inner_angles():
    assert default_inner_angle("linear", 40.0) == pytest.approx(30.0)
    assert default_inner_angle("smoothstep", 40.0) == pytest.approx(30.0)
    assert default_inner_angle("smoothstep", 6.0) == 0.0
    want = math.degrees(2 * math.atan(math.tan(math.radians(20)) * 46 / 64))
    assert default_inner_angle("unity", 40.0) == pytest.approx(want)
    packed = pack_lights(Scene(lights=(Light(type="spot", spot_angle=40.0, cone="unity"),)))
    ci, co = packed.floats[0, F_COS_INNER], packed.floats[0, F_COS_OUTER]
    assert ci == pytest.approx(math.cos(math.radians(want / 2)))
    assert packed.floats[0, F_UNITY_A] == pytest.approx(1 / (ci - co))
    assert packed.floats[0, F_UNITY_B] == pytest.approx(-co / (ci - co))


def _cookie_file(tmp_path, img, name="c.png"):
    path = tmp_path / name
    iio.imwrite(path, img)
    return str(path)


def test_cookie_load_flips_rows_and_picks_channels(tmp_path):
    img = np.zeros((2, 3, 4), dtype=np.uint8)
    img[0, :, 0] = 255  # top row red
    img[:, :, 3] = 51
    path = _cookie_file(tmp_path, img)
    rgb = load_cookie(Cookie(path=path, channel="rgb"), "s", "k")
    assert rgb.shape == (2, 3, 3)
    np.testing.assert_array_equal(rgb[1, :, 0], 1.0)  # top of the picture is the last row (v = 1)
    np.testing.assert_array_equal(rgb[0, :, 0], 0.0)
    np.testing.assert_allclose(load_cookie(Cookie(path=path, channel="alpha"), "s", "k"), 0.2)
    lum = load_cookie(Cookie(path=path, channel="luminance"), "s", "k")
    np.testing.assert_allclose(lum[1, :, 1], 0.2126)


def test_texture_sampling_filters_and_wraps():
    tex = np.array([[0.0, 1.0], [2.0, 3.0]])  # (h, w) = (2, 2), row 0 = v < 0.5
    texels = np.repeat(tex.reshape(-1, 1), 3, axis=1)
    s = lambda u, v, rep, near: sample_texture(texels, 0, 2, 2, rep, near, u, v)[0]  # noqa: E731
    assert s(0.5, 0.5, False, False) == pytest.approx(1.5)
    assert s(0.25, 0.25, False, False) == pytest.approx(0.0)
    assert s(0.0, 0.25, False, False) == pytest.approx(0.0)  # clamp
    assert s(0.0, 0.25, True, False) == pytest.approx(0.5)  # repeat blends with the far column
    assert s(0.74, 0.8, False, True) == 3.0
    assert s(1.3, 0.2, True, True) == 0.0
    assert s(1.3, 0.2, False, True) == 1.0


def test_spot_cookie_projection_and_incidence(tmp_path):
    img = np.zeros((4, 4), dtype=np.uint8)
    img[0:2, 2:4] = 255  # top-right quadrant of the picture is lit
    path = _cookie_file(tmp_path, img)
    light = Light(type="spot", position=(0.0, 0.0, 0.0), direction=(0.0, 0.0, 1.0), spot_angle=90.0,
                  cookie=Cookie(path=path, filter="nearest"), range=100.0, cone="smoothstep", inner_spot_angle=90.0)
    p = pack_lights(Scene(lights=(light,)))
    assert spot_cookie_uv(1.0, 0.0, 1.0, 1.0) == pytest.approx((1.0, 0.5))
    # light frame of direction +z is the world frame (right = +x, up = +y)
    bright = light_incidence(p, 0, 0.3, 0.3, 2.0)
    dark = light_incidence(p, 0, -0.3, 0.3, 2.0)
    assert bright[4] == pytest.approx(1.0 / (0.18 + 4.0)) and dark[4] == 0.0


def test_incidence_of_each_light_type():
    lights = (Light(type="point", position=(1.0, 2.0, 3.0), color=(1.0, 0.5, 0.25), intensity=8.0, range=10.0),
              Light(type="directional", direction=(0.0, -1.0, 0.0), intensity=3.0),
              Light(type="spot", position=(0.0, 5.0, 0.0), direction=(0.0, -1.0, 0.0), spot_angle=60.0,
                    intensity=2.0, range=20.0))
    p = pack_lights(Scene(lights=lights))
    lx, ly, lz, dist, er, eg, eb = light_incidence(p, 0, 1.0, 2.0, 5.0)
    assert (lx, ly, lz, dist) == pytest.approx((0.0, 0.0, -1.0, 2.0))
    assert (er, eg, eb) == pytest.approx((2.0, 1.0, 0.5))
    assert light_incidence(p, 0, 1.0, 2.0, 13.5)[4] == 0.0  # beyond range
    out = light_incidence(p, 1, 7.0, -3.0, 1.0)
    assert out[:3] == pytest.approx((0.0, 1.0, 0.0)) and out[3] == np.inf and out[4:] == pytest.approx((3.0,) * 3)
    on_axis = light_incidence(p, 2, 0.0, 1.0, 0.0)
    assert on_axis[4] == pytest.approx(2.0 / 16.0)
    assert light_incidence(p, 2, 3.0, 4.0, 0.0)[4] == 0.0  # outside the cone
    assert p.floats[0, F_CR] == 8.0


def test_scene_colour_applies_the_lights_shadow_strength_to_surfaces():
    """Surfaces see ``V = 1 - strength (1 - tr)`` as the march does (docs/PHYSICS.md): the colour is affine in
    the strength, strength 0 lights the shadow as if the occluder cast none, strength 1 is the exact shadow."""
    def colour(strength):
        light = Light(type="point", position=(0.0, 4.0, 0.0), intensity=40.0, range=20.0,
                      shadows=ShadowSettings(strength=strength))
        scene = Scene(render=RenderSettings(width=40, height=30, ambient=(0.05, 0.05, 0.05)),
                      camera=CameraSettings(position=(0.0, 6.0, -6.0), look_at=(0.0, 0.0, 0.5)), lights=(light,),
                      objects=(Plane(), Box(center=(0.0, 2.0, 0.0), size=(1.0, 0.2, 1.0))))
        return prepare_frame(scene).scene_colour

    full, none, some = colour(1.0), colour(0.0), colour(0.3)
    shadow = np.all(none > full + 1e-3, axis=2)   # receiver pixels the box shadows
    assert shadow.sum() > 20 and np.allclose(full[shadow], 0.8 * 0.05)       # albedo x ambient only
    np.testing.assert_allclose(some, full + 0.7 * (none - full), rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("shadows", [None, ShadowSettings(enabled=False)])
def test_a_light_without_shadows_lights_surfaces_as_unoccluded_lambert(shadows):
    """A light whose shadows are absent or disabled casts none on surfaces, as in the medium (docs/PHYSICS.md): the
    ground under a box, which the same sun with shadows leaves at the ambient, is lit by the closed form
    ``albedo (I cos(theta) / pi + ambient)`` of a white directional light of irradiance I at incidence theta."""
    direction = np.array([1.0, -1.0, 0.3])
    albedo, ambient, intensity = 0.6, 0.05, 2.5

    def colour(sh):
        light = Light(type="directional", direction=tuple(direction), intensity=intensity, shadows=sh)
        scene = Scene(render=RenderSettings(width=40, height=30, ambient=(ambient,) * 3),
                      camera=CameraSettings(position=(0.0, 6.0, -6.0), look_at=(0.0, 0.0, 0.5)), lights=(light,),
                      objects=(Plane(material=Material(albedo=(albedo,) * 3)),
                               Box(center=(0.0, 1.5, 0.0), size=(3.0, 0.2, 3.0))))
        frame = prepare_frame(scene)
        return frame.scene_colour, frame.gbuffer

    got, g = colour(shadows)
    shadowed, _ = colour(ShadowSettings())
    ground = np.isfinite(g.depth) & (np.abs(g.position[..., 1]) < 1e-9)
    cos_theta = -direction[1] / np.linalg.norm(direction)
    want = albedo * (intensity * cos_theta / math.pi + ambient)
    under_box = ground & np.all(np.isclose(shadowed, albedo * ambient, rtol=1e-12), axis=2)
    assert under_box.sum() > 20                                   # the sun with shadows leaves these at ambient
    np.testing.assert_allclose(got[ground], want, rtol=1e-12)     # without, every ground pixel is lit


def test_scene_colour_is_the_sum_over_lights_of_the_shadow_rays_pixel_by_pixel(tmp_path):
    """The scene colour kernel (its shadow query compiled into the pixel loop) gives, bit for bit, the module's
    formula evaluated pixel by pixel with the separately compiled shadow query: lights in order, each
    ``E · cos · V`` with ``V`` the RGB shadow ray through transparent primitives and a transparent mesh (the
    tree of opaque primitives, the linear list and the triangle tree), partial strength, sky pixels."""
    write_obj(tmp_path / "tet.obj", np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
              np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))
    glass = Material(opacity=0.4, tint=(1.0, 0.6, 0.3))
    lights = (Light(type="point", position=(0.5, 4.0, 0.0), intensity=40.0, range=20.0,
                    shadows=ShadowSettings(strength=0.7)),
              Light(type="spot", position=(-2.0, 5.0, -1.0), direction=(0.4, -1.0, 0.3), spot_angle=70.0,
                    intensity=60.0, range=25.0, shadows=ShadowSettings()),
              Light(type="directional", direction=(0.3, -1.0, 0.4), intensity=1.5, shadows=ShadowSettings()),
              Light(type="point", position=(2.0, 1.0, -2.0), intensity=5.0, range=10.0))
    objects = (Plane(), Box(center=(0.0, 1.5, 0.0), size=(1.0, 0.2, 1.0)),
               Sphere(center=(1.5, 1.0, 0.5), radius=0.6, material=glass),
               Cylinder(center=(-1.5, 1.0, 0.5), radius=0.3, height=2.0),
               Mesh(path=str(tmp_path / "tet.obj"), position=(-0.5, 2.5, -0.5), material=glass))
    scene = Scene(render=RenderSettings(width=48, height=32, ambient=(0.05, 0.04, 0.03), sky_color=(0.1, 0.2, 0.3)),
                  camera=CameraSettings(position=(0.0, 4.0, -7.0), look_at=(0.0, 0.5, 0.5)), lights=lights,
                  objects=objects)
    frame = prepare_frame(scene)
    g, geo, packed = frame.gbuffer, frame.geometry.arrays, frame.lights.astype(np.float64)
    strength = [li.shadows.strength if li.shadows is not None else 0.0 for li in lights]
    want = np.empty_like(frame.scene_colour)
    lit = shadowed = tinted = 0
    for y, j in np.ndindex(g.object_id.shape):
        obj = g.object_id[y, j]
        if obj < 0:
            want[y, j] = scene.render.sky_color
            continue
        x, yy, z = ((g.origin[c] + g.distance[y, j] * g.directions[y, j, c]) + SURFACE_OFFSET * g.normal[y, j, c]
                    for c in range(3))
        s = [0.0, 0.0, 0.0]
        for k in range(len(lights)):
            lx, ly, lz, dist, *e = light_incidence(packed, k, x, yy, z)
            cos_n = g.normal[y, j, 0] * lx + g.normal[y, j, 1] * ly + g.normal[y, j, 2] * lz
            if cos_n <= 0.0 or e[0] + e[1] + e[2] == 0.0:
                continue
            v = (1.0, 1.0, 1.0)
            if strength[k] > 0.0:
                v = shadow_transmittance(geo, x, yy, z, lx, ly, lz, dist)
                shadowed += v != (1.0, 1.0, 1.0)
                tinted += 0.0 < v[2] < v[0] < 1.0
                if strength[k] < 1.0:
                    v = apply_strength(strength[k], *v)
            lit += 1
            s = [s[c] + e[c] * cos_n * v[c] for c in range(3)]
        want[y, j] = [g.object_albedo[obj, c] * (s[c] * (1.0 / math.pi) + scene.render.ambient[c])
                      + g.object_emission[obj, c] for c in range(3)]
    assert lit > 2000 and shadowed > 150 and tinted > 20 and np.any(g.object_id < 0)
    assert want.tobytes() == frame.scene_colour.tobytes()
