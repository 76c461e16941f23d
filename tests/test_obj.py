"""OBJ loading: statements, fan triangulation, index forms, errors naming file and line; the bundled mesh."""

from pathlib import Path

import numpy as np
import pytest

from vlref.camera import euler_matrix
from vlref.errors import InputError
from vlref.geometry.meshgen import colonnade
from vlref.geometry.obj import load_obj, transform_vertices, write_obj

DATA = Path(__file__).resolve().parents[1] / "data" / "scenes"


def write(tmp_path, text):
    p = tmp_path / "m.obj"
    p.write_text(text)
    return p


def test_vertices_faces_fans_negative_and_slash_indices(tmp_path):
    p = write(tmp_path, """# a quad, a triangle by negative indices, slash forms
mtllib x.mtl
o thing
v 0 0 0
v 1 0 0
v 1 1 0 1.0
v 0 1 0
vt 0 0
vn 0 0 1
f 1 2 3 4
v 0 0 1   # trailing comment
f -1 -4/1 -3//1
f 1/1/1 2/1/1 5/1/1
s off
""")
    v, f = load_obj(p)
    assert v.dtype == np.float64 and f.dtype == np.int64
    assert np.array_equal(v, [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1]])
    assert np.array_equal(f, [[0, 1, 2], [0, 2, 3], [4, 1, 2], [0, 1, 4]])


@pytest.mark.parametrize("line,reason", [
    ("v 1 2", "3 coordinates"),
    ("v 1 x 3", "must be numbers"),
    ("v nan 0 0", "finite"),
    ("f 1 2", "at least 3 vertices"),
    ("f 1 2 9", "out of range"),
    ("f 0 1 2", "out of range"),
    ("f -4 1 2", "out of range"),
    ("f 1/2 a 3", "bad vertex reference"),
])
def test_bad_lines_name_file_and_line(tmp_path, line, reason):
    p = write(tmp_path, "v 0 0 0\nv 1 0 0\n\nv 0 1 0\n" + line + "\nf 1 2 3\n")
    with pytest.raises(InputError) as err:
        load_obj(p)
    assert err.value.file == str(p) and err.value.path == "line 5" and reason in err.value.reason
    assert str(p) in str(err.value) and "line 5" in str(err.value)


def test_missing_file_and_empty_mesh(tmp_path):
    with pytest.raises(InputError, match="cannot read"):
        load_obj(tmp_path / "nope.obj")
    with pytest.raises(InputError, match="no faces"):
        load_obj(write(tmp_path, "v 0 0 0\n"))


def test_write_then_load_round_trips_bits(tmp_path):
    rng = np.random.default_rng(3)
    v, f = rng.normal(size=(20, 3)), rng.integers(0, 20, size=(30, 3))
    write_obj(tmp_path / "r.obj", v, f, "two\nlines")
    v2, f2 = load_obj(tmp_path / "r.obj")
    assert np.array_equal(v, v2) and np.array_equal(f, f2)


def test_transform_is_scale_then_rotate_then_translate():
    v = np.array([[1.0, 2.0, 3.0], [0.0, 0.0, 0.0]])
    out = transform_vertices(v, (1, 2, 3), (10, 20, 30), (2, 3, 4))
    expect = euler_matrix((10, 20, 30)) @ np.array([2.0, 6.0, 12.0]) + [1, 2, 3]
    assert np.allclose(out[0], expect, atol=1e-14) and np.array_equal(out[1], [1.0, 2.0, 3.0])


def test_bundled_colonnade_is_the_generator_output():
    v, f = load_obj(DATA / "colonnade.obj")
    gv, gf = colonnade()
    assert np.array_equal(v, gv) and np.array_equal(f, gf)
    assert 2000 <= len(f) <= 5000
    # closed and consistently wound: every directed edge once, outward (positive) volume
    edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    assert len(np.unique(edges, axis=0)) == len(edges)
    assert len(np.unique(np.sort(edges, axis=1), axis=0)) * 2 == len(edges)
    t = v[f]
    volume = np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2])).sum() / 6.0
    assert volume > 0
