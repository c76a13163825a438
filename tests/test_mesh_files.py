"""Mesh files: a malformed, truncated or hostile file is a `MeshFileError` naming the file and what
is wrong (never a raw exception, a process exit, or an allocation beyond the file's size); real
files read (OBJ texture/normal indices, negative indices, mixed polygons); the clean-up functions
report exactly what they changed and never modify their input."""

import pickle
import resource
import struct
import time

import numpy as np
import pytest

from ddgjax import mesh
from ddgjax.errors import DDGError, InvalidInputError, MeshFileError, NonFiniteError, NonManifoldError

HEADER_PLY = b"ply\nformat %s 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
FACE_PLY = b"element face %d\nproperty list uchar int vertex_indices\nend_header\n"
HEADER_VTK = b"# vtk DataFile Version 4.2\nmesh\n%s\nDATASET UNSTRUCTURED_GRID\n"


def _binary_stl(triangles: np.ndarray, count: int | None = None) -> bytes:
    """A binary STL of (nf, 3, 3) corners; `count` overrides the triangle count of the header."""
    record = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])
    data = np.zeros(len(triangles), dtype=record)
    data["corners"] = triangles
    return b"\0" * 80 + struct.pack("<I", len(triangles) if count is None else count) + data.tobytes()


def _ascii_stl(triangles) -> bytes:
    facets = "".join("facet normal 0 0 1\n outer loop\n" + "".join(f"  vertex {x} {y} {z}\n" for x, y, z in t)
                     + " endloop\nendfacet\n" for t in triangles)
    return f"solid s\n{facets}endsolid s\n".encode()


TRIANGLE = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]])

HOSTILE = {  # a few bytes whose header asks for billions of items
    "huge.off": b"OFF\n3000000000 1 0\n0 0 0\n",
    "huge_ascii.ply": HEADER_PLY % (b"ascii", 3_000_000_000) + FACE_PLY % 1,
    "huge_binary.ply": HEADER_PLY % (b"binary_little_endian", 3) + FACE_PLY % 2_000_000_000 + bytes(36),
    "huge.stl": _binary_stl(TRIANGLE, count=3_000_000_000),
    "huge_points.vtk": HEADER_VTK % b"ASCII" + b"POINTS 3000000000 float\n0 0 0\n",
    "huge_cells.vtk": HEADER_VTK % b"BINARY" + b"POINTS 3 float\n" + bytes(36) + b"\nCELLS 1 2000000000\n",
}


def _write(tmp_path, name: str, data: bytes):
    path = tmp_path / name
    path.write_bytes(data)
    return path


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_a_huge_count_in_a_header_is_refused_before_allocating(tmp_path, name):
    """25 bytes of OFF asking for 3·10⁹ vertices used to allocate 67 GiB: now an error within a
    second and less than 200 MB of memory, naming the file and the promise."""
    path = _write(tmp_path, name, HOSTILE[name])
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    start = time.perf_counter()
    with pytest.raises(MeshFileError, match="promises") as caught:
        mesh.read(path)
    assert time.perf_counter() - start < 1.0
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - rss < 200_000  # kilobytes on Linux
    assert str(path) in str(caught.value) and caught.value.path == path


def test_the_off_promise_is_stated_in_bytes(tmp_path):
    path = _write(tmp_path, "huge.off", HOSTILE["huge.off"])
    with pytest.raises(MeshFileError, match=r"3000000000 vertices and 1 faces, which take at least 18000000007 "
                                            r"bytes, but the file has only 25 bytes"):
        mesh.read(path)


TRUNCATED = {
    "short.off": (b"OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n", "ends after 1 of its 2 faces"),
    "short.ply": (HEADER_PLY % (b"ascii", 3) + FACE_PLY % 1 + b"0 0 0\n1 0 0\n", "promises 3 vertex, 1 face"),
    "noheader.ply": (b"ply\nformat ascii 1.0\nelement vertex 3\n", "ends inside its header"),
    "short.stl": (_binary_stl(TRIANGLE)[:-10], "promises 1 binary triangles, which take at least 134 bytes, but the "
                                               "file has only 124"),
    "long.stl": (_binary_stl(TRIANGLE) + bytes(10), "a binary STL of 1 triangles has 134 bytes, this file 144"),
    "open.stl": (_ascii_stl(TRIANGLE).replace(b" endloop\nendfacet\nendsolid s\n", b""), "ends inside facet 0"),
    "tiny.stl": (b"abc", "neither an ascii STL"),
    "short.vtk": (HEADER_VTK % b"ASCII" + b"POINTS 4 double\n0 0 0 1 0 0\n", "cannot be read as VTK"),
}


@pytest.mark.parametrize("name", sorted(TRUNCATED))
def test_a_truncated_file_names_what_is_missing(tmp_path, name):
    data, message = TRUNCATED[name]
    with pytest.raises(MeshFileError, match=message):
        mesh.read(_write(tmp_path, name, data))


MALFORMED = {
    "words.off": (b"OFF\n3 1 0\n0 0 0\n1 0 zero\n0 1 0\n3 0 1 2\n", "line 4: vertex 1 '1 0 zero' is not a list of numbers"),
    "binary.off": (b"\0\1\2\3 garbage", "is a binary file"),
    "notoff.off": (b"PLY\n", "expected the keyword OFF"),
    "more.off": (b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 1\n", "line 7: more data after the 3 vertices and 1 faces"),
    "corners.off": (b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", "face 0 announces 4 corners but lists 3"),
    "words.obj": (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", "line 4: the face corner 'x' is not an integer"),
    "zero.obj": (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "line 4: the face corner '0' refers to no vertex"),
    "back.obj": (b"v 0 0 0\nv 1 0 0\nf -3 -2 -1\n", "the face corner '-3' refers to no vertex"),
    "edge.obj": (b"v 0 0 0\nv 1 0 0\nf 1 2\n", "face 0 has 2 corners; a face needs at least 3"),
    "points.obj": (b"v 0 0 0\nv 1 0 0\n", "contains no surface cells"),
    "noxyz.ply": (HEADER_PLY.replace(b" z\n", b" w\n") % (b"ascii", 3) + FACE_PLY % 1 + b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                  "no element 'vertex' with properties x, y, z"),
    "format.ply": (b"ply\nformat ascii 2.0\nend_header\n", "unexpected PLY header line 'format ascii 2.0'"),
    "polydata.vtk": (b"# vtk DataFile Version 4.2\nm\nASCII\nDATASET POLYDATA\n", "the POLYDATA has no POINTS section"),
    "grid.vtk": (b"# vtk DataFile Version 4.2\nm\nASCII\nDATASET STRUCTURED_POINTS\n",
                 "only UNSTRUCTURED_GRID and POLYDATA are read"),
    "counts.vtk": (b"# vtk DataFile Version 4.2\nm\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\n"
                   b"POLYGONS 2 5\n3 0 1 2 7\n", "promises 2 polygons in 5 numbers, which do not add up"),
    "garbage.msh": (b"not a mesh at all", "Couldn't read file"),
}


@pytest.mark.parametrize("name", sorted(MALFORMED))
def test_a_malformed_file_names_the_line_or_element(tmp_path, name):
    data, message = MALFORMED[name]
    with pytest.raises(MeshFileError, match=message):
        mesh.read(_write(tmp_path, name, data))


def test_missing_files_and_directories(tmp_path):
    with pytest.raises(MeshFileError, match="no such file"):
        mesh.read(tmp_path / "missing.obj")
    with pytest.raises(MeshFileError, match="is not a regular file"):
        mesh.read(tmp_path)


def test_meshio_calling_sys_exit_is_an_error_not_the_end_of_the_process(tmp_path, monkeypatch):
    """meshio.read ends a failed read with sys.exit(1) (the .msh case above); any reader's
    SystemExit or exception becomes a MeshFileError; KeyboardInterrupt still interrupts."""
    import meshio.ply

    path = tmp_path / "t.ply"
    mesh.write(path, *mesh.tetrahedron())
    for raised, expected in ((SystemExit(1), "the reader gave up"), (RecursionError("deep"), "RecursionError: deep")):
        def fail(_, raised=raised):
            raise raised
        monkeypatch.setattr(meshio.ply, "read", fail)
        with pytest.raises(MeshFileError, match=expected):
            mesh.read(path)

    def interrupt(_):
        raise KeyboardInterrupt
    monkeypatch.setattr(meshio.ply, "read", interrupt)
    with pytest.raises(KeyboardInterrupt):
        mesh.read(path)


NAN = {
    "nan.off": b"OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n",
    "inf.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 inf\nf 1 2 3\n",
    "nan.ply": HEADER_PLY % (b"ascii", 3) + FACE_PLY % 1 + b"0 0 0\n1 0 0\nnan 1 0\n3 0 1 2\n",
    "nan.stl": _binary_stl(np.array([[[0, 0, 0], [1, 0, 0], [0, np.nan, 0]]])),
}


@pytest.mark.parametrize("name", sorted(NAN))
def test_non_finite_coordinates_name_the_vertex(tmp_path, name):
    vertex = {"nan.off": 1, "inf.obj": 2, "nan.ply": 2, "nan.stl": 2}[name]
    with pytest.raises(MeshFileError, match=f"vertex {vertex} has the non-finite coordinates"):
        mesh.read(_write(tmp_path, name, NAN[name]))


OUT_OF_RANGE = {
    "range.off": b"OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 3\n",
    "range.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n",
    "range.ply": HEADER_PLY % (b"ascii", 3) + FACE_PLY % 2 + b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 3\n",
}


@pytest.mark.parametrize("name", sorted(OUT_OF_RANGE))
def test_a_face_index_out_of_range_names_the_face(tmp_path, name):
    with pytest.raises(MeshFileError, match=r"face 1 refers to vertex 3 \(0-based\), but the file has 3 vertices"):
        mesh.read(_write(tmp_path, name, OUT_OF_RANGE[name]))


def test_mesh_file_error_is_a_ddg_error_and_pickles(tmp_path):
    error = MeshFileError(tmp_path / "m.off", "no such file")
    copy = pickle.loads(pickle.dumps(error))
    assert isinstance(copy, DDGError) and str(copy) == str(error) and copy.path == error.path


# --- real files -----------------------------------------------------------------------------


CUBE_V, CUBE_F = mesh.cube()


def _obj(V, faces: list[str], extra: str = "") -> bytes:
    return ("".join(f"v {x} {y} {z}\n" for x, y, z in V) + extra + "".join(f"f {f}\n" for f in faces)).encode()


def test_obj_texture_normal_and_negative_indices_read_as_the_plain_file(tmp_path):
    """`f 1/1/1 ...`, `f 1//1 ...`, `f 1/1 ...` and relative `f -8 ...` give the faces of the plain
    `f 1 2 3 4` file; vt, vn, o, g, s, usemtl, l lines and comments are skipped."""
    plain = [" ".join(str(i + 1) for i in f) for f in CUBE_F]
    styles = [lambda i: f"{i}/{i}/{i}", lambda i: f"{i}//1", lambda i: f"{i}/3", lambda i: f"{i - 9}"]
    decorated = [" ".join(styles[k % 4](i + 1) for i in f) for k, f in enumerate(CUBE_F)]
    extra = "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\no cube\ng side\ns off\nusemtl red\nl 1 2\n# a comment\n"
    V1, F1 = mesh.read(_write(tmp_path, "plain.obj", _obj(CUBE_V, plain)))
    V2, F2 = mesh.read(_write(tmp_path, "textured.obj", _obj(CUBE_V, decorated, extra)))
    assert F1.shape == (6, 4) and np.array_equal(F1, CUBE_F) and np.array_equal(F2, F1)
    assert np.array_equal(V1, CUBE_V) and np.array_equal(V2, V1)


def test_obj_extra_vertex_components_and_line_continuations(tmp_path):
    data = b"v 0 0 0 1.0\nv 1 0 0 0.5 0.5 0.5\nv 0 1 0\nf 1 \\\n 2 3\n"
    V, F = mesh.read(_write(tmp_path, "w.obj", data))
    assert V.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0]] and F.tolist() == [[0, 1, 2]]


MIXED_V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0.5, 0]], dtype=float)
MIXED_F = [[1, 4, 2], [0, 1, 2, 3]]  # `write` groups faces by size, smallest first


@pytest.mark.parametrize("suffix", [".obj", ".off", ".ply", ".vtk"])
def test_mixed_triangles_and_quads_come_back_as_polygons(tmp_path, suffix):
    mesh.write(tmp_path / f"m{suffix}", MIXED_V, MIXED_F)
    V, F = mesh.read(tmp_path / f"m{suffix}")
    assert np.array_equal(V, MIXED_V) and F == MIXED_F
    assert mesh.euler_characteristic(F) == 1


def _polydata(encoding: bytes, points: bytes, polygons: bytes) -> bytes:
    return b"# vtk DataFile Version 3.0\nm\n" + encoding + b"\nDATASET POLYDATA\n" + points + polygons


def test_vtk_polydata_with_a_polygon_of_many_corners(tmp_path):
    """POLYDATA as ParaView writes it: classic ascii and big-endian binary (`POLYGONS n size`, each
    polygon its corner count then its corners) and the VTK 5.1 layout (OFFSETS, CONNECTIVITY); a
    200-gon (more corners than a signed byte counts) next to a triangle."""
    n = 200
    t = 2 * np.pi * np.arange(n) / n
    V = np.column_stack([np.cos(t), np.sin(t), np.zeros(n)]).astype(np.float32).astype(np.float64)
    F = [list(range(n)), [0, 1, 2]]
    flat = np.array([n, *range(n), 3, 0, 1, 2])
    ascii_points = b"POINTS %d float\n" % n + " ".join(map(repr, V.ravel().tolist())).encode() + b"\n"
    files = {
        "ascii.vtk": _polydata(b"ASCII", ascii_points,
                               b"POLYGONS 2 %d\n" % flat.size + " ".join(map(str, flat)).encode() + b"\n"),
        "binary.vtk": _polydata(b"BINARY", b"POINTS %d float\n" % n + V.astype(">f4").tobytes() + b"\n",
                                b"POLYGONS 2 %d\n" % flat.size + flat.astype(">i4").tobytes() + b"\n"),
        "v51.vtk": _polydata(b"ASCII", ascii_points, b"POLYGONS 3 %d\nOFFSETS vtktypeint64\n0 %d %d\n"
                             b"CONNECTIVITY vtktypeint64\n" % (n + 3, n, n + 3)
                             + " ".join(map(str, [*range(n), 0, 1, 2])).encode() + b"\n"),
    }
    for name, data in files.items():
        V2, F2 = mesh.read(_write(tmp_path, name, data))
        assert np.array_equal(V2, V) and F2 == F, name


def test_polygons_keep_the_order_of_the_file(tmp_path):
    V, F = mesh.read(_write(tmp_path, "q.obj", _obj(MIXED_V, ["1 2 3 4", "2 5 3", "1 2 5 3 4"])))
    assert F == [[0, 1, 2, 3], [1, 4, 2], [0, 1, 4, 2, 3]]


def test_triangulate_accepts_what_read_returns_for_mixed_files(tmp_path):
    mesh.write(tmp_path / "m.off", MIXED_V, MIXED_F)
    T = mesh.triangulate(mesh.read(tmp_path / "m.off")[1])
    assert np.asarray(T).tolist() == [[1, 4, 2], [0, 1, 2], [0, 2, 3]]


def test_off_keeps_quads(tmp_path):
    """meshio's OFF writer dropped every face but triangles; written here, the cube's quads stay."""
    mesh.write(tmp_path / "cube.off", CUBE_V, CUBE_F)
    V, F = mesh.read(tmp_path / "cube.off")
    assert np.array_equal(V, CUBE_V) and np.array_equal(F, CUBE_F)


def test_stl_ascii_and_binary_weld_the_corners_of_a_closed_surface(tmp_path):
    """The octahedron stored as 8 separate triangles (24 corners) reads back as 6 vertices, χ = 2."""
    V, F = mesh.octahedron()
    triangles = np.asarray(V)[np.asarray(F)]
    for name, data in (("a.stl", _ascii_stl(triangles)), ("b.stl", _binary_stl(triangles))):
        V2, F2 = mesh.read(_write(tmp_path, name, data))
        assert V2.shape == (6, 3) and F2.shape == (8, 3)
        assert np.array_equal(V2[F2], triangles) and mesh.euler_characteristic(F2) == 2


# --- clean-up ---------------------------------------------------------------------------------


def _sphere():
    V, F = mesh.icosphere(1)
    return np.asarray(V, dtype=float), np.asarray(F)


def _unchanged(V, F, fn, *args):
    """Run fn(V, F, *args) and check that V and F are as before."""
    V0, F0 = np.copy(V), [list(f) for f in F] if isinstance(F, list) else np.copy(F)
    out = fn(V, F, *args)
    assert np.array_equal(V, V0, equal_nan=True) and (F == F0 if isinstance(F, list) else np.array_equal(F, F0))
    return out


CLEANUPS = [(mesh.remove_unreferenced_vertices, ()), (mesh.weld_vertices, (1e-6,)),
            (mesh.split_nonmanifold_vertices, ()), (mesh.drop_degenerate_faces, ())]


@pytest.mark.parametrize("fn, args", CLEANUPS, ids=lambda x: getattr(x, "__name__", ""))
def test_a_clean_mesh_reports_no_change(fn, args):
    """Negative control: the icosphere (42 vertices, 80 faces) comes back as it was, count 0."""
    V, F = _sphere()
    V2, F2, report = _unchanged(V, F, fn, *args)
    assert report.count == 0 and report.vertices == () and report.faces == ()
    assert np.array_equal(V2, V) and np.array_equal(F2, F) and V2 is not V
    assert np.array_equal(report.vertex_map, np.arange(42)) and np.array_equal(report.face_origin, np.arange(80))


def test_remove_unreferenced_vertices():
    V, F = _sphere()
    stray = np.array([[9.0, 9, 9], [np.nan, 0, 0], [7.0, 7, 7]])
    Vs = np.vstack([stray[:1], V[:5], stray[1:2], V[5:], stray[2:]])  # strays at 0, 6 and 44
    Fs = np.where(F < 5, F + 1, F + 2)
    V2, F2, report = _unchanged(Vs, Fs, mesh.remove_unreferenced_vertices)
    assert report.count == 3 and report.vertices == (0, 6, 44)
    assert np.array_equal(V2, V) and np.array_equal(F2, F)
    assert report.vertex_map[[0, 6, 44]].tolist() == [-1, -1, -1] and report.vertex_map[7] == 5
    V3, F3, report = mesh.remove_unreferenced_vertices(Vs, [list(f) for f in Fs])  # a list stays a list
    assert isinstance(F3, list) and F3 == F.tolist()


def test_weld_vertices_of_a_triangle_soup():
    """Each of the 80 faces with its own corners (240 vertices, as in an STL file): welding exact
    duplicates (tol 0) merges 198 and gives back the 42 vertices and the sphere (χ = 2); with
    the corners jittered by at most 1e-9, tol 1e-6 merges the same 198 and tol 1e-12 none."""
    V, F = _sphere()
    soup, faces = V[F].reshape(-1, 3), np.arange(240).reshape(80, 3)
    V2, F2, report = _unchanged(soup, faces, mesh.weld_vertices, 0.0)
    assert report.count == 198 and len(V2) == 42 and mesh.euler_characteristic(F2) == 2
    assert np.array_equal(V2[F2], V[F]) and report.kinds == {"faces_repeating_a_vertex": 0}
    assert np.all(np.diff(report.vertex_origin) > 0)  # each cluster kept its vertex of lowest index
    jittered = soup + np.random.default_rng(0).uniform(-1e-9, 1e-9, soup.shape)
    V3, F3, report = mesh.weld_vertices(jittered, faces, 1e-6)
    assert report.count == 198 and np.max(np.abs(V3[F3] - V[F])) <= 2e-9
    assert mesh.weld_vertices(jittered, faces, 1e-12)[2].count == 0


def test_weld_vertices_counts_faces_that_collapse_and_checks_tol():
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1e-8, 0], [0, 1, 0]], dtype=float)
    V2, F2, report = mesh.weld_vertices(V, np.array([[0, 1, 2], [0, 2, 3]]), 1e-6)
    assert report.count == 1 and report.vertices == (2,) and F2.tolist() == [[0, 1, 1], [0, 1, 2]]
    assert report.kinds == {"faces_repeating_a_vertex": 1} and report.vertex_map.tolist() == [0, 1, 1, 2]
    for tol in (-1.0, np.nan, np.inf):
        with pytest.raises(InvalidInputError, match="tol must be finite and >= 0"):
            mesh.weld_vertices(V, np.array([[0, 1, 2]]), tol)
    with pytest.raises(NonFiniteError, match="vertex 1"):
        mesh.weld_vertices(V * np.array([[1], [np.nan], [1], [1]]), np.array([[0, 1, 2]]), 0.0)


def test_split_two_spheres_touching_at_a_vertex():
    """Two icospheres sharing vertex 0 (83 vertices): vertex 0 has two fans, `from_faces` refuses
    the surface; split, vertex 83 is the copy, and the result is two spheres (χ = 4)."""
    V, F = _sphere()
    V2 = np.vstack([V, 2 * V[0] - V[1:]])  # the second sphere: the first reflected through vertex 0
    second = F + 41
    second[F == 0] = 0
    F2 = np.vstack([F, second])
    with pytest.raises(NonManifoldError, match="vertex 0"):
        mesh.from_faces(F2)
    V3, F3, report = _unchanged(V2, F2, mesh.split_nonmanifold_vertices)
    assert report.count == 1 and report.vertices == (0,) and len(V3) == 84
    assert report.vertex_origin[83] == 0 and np.array_equal(V3[83], V3[0])
    assert np.array_equal(F3[:80], F) and np.sum(F3 == 83) == 5
    assert mesh.euler_characteristic(F3) == 4 and len(mesh.connected_components(F3)) == 2


def test_split_a_bowtie_given_as_polygons():
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [-1, 0, 0], [-1, -1, 0]], dtype=float)
    F = [[0, 1, 2], [0, 3, 4]]
    V2, F2, report = _unchanged(V, F, mesh.split_nonmanifold_vertices)
    assert report.count == 1 and F2 == [[0, 1, 2], [5, 3, 4]] and report.vertex_origin.tolist() == [0, 1, 2, 3, 4, 0]


def test_drop_degenerate_faces_at_every_scale():
    """Faces 0 (collinear corners), 2 (a repeated vertex) and 4 (a quad on a line) go; the
    triangle 1 and the quad 3 stay; the same at coordinates 1e-150 and 1e150."""
    V = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [3, 0, 0]], dtype=float)
    F = [[0, 1, 2], [0, 1, 3], [0, 0, 3], [0, 1, 3, 2], [0, 1, 2, 4]]
    for scale in (1.0, 1e-150, 1e150):
        V2, F2, report = _unchanged(V * scale, F, mesh.drop_degenerate_faces)
        assert F2 == [[0, 1, 3], [0, 1, 3, 2]] and report.faces == (0, 2, 4) and report.count == 3
        assert report.kinds == {"repeated_vertex": 1, "zero_area": 2} and report.face_origin.tolist() == [1, 3]
    near = V + np.array([[0, 0, 0], [0, 0, 0], [0, 1e-9, 0], [0, 0, 0], [0, 0, 0]])  # sin² ≈ 2.5e-19: still flat
    assert mesh.drop_degenerate_faces(near, F[:1])[2].count == 1
    thin = V + np.array([[0, 0, 0], [0, 0, 0], [0, 1e-6, 0], [0, 0, 0], [0, 0, 0]])  # sin² ≈ 2.5e-13: a sliver
    assert mesh.drop_degenerate_faces(thin, F[:1])[2].count == 0


def test_cleanup_pipeline_on_a_downloaded_mesh(tmp_path):
    """An STL of the octahedron plus a zero-area triangle: read (6 + 1 vertices, 9 faces), drop
    the flat face, remove the vertex it left behind: the octahedron, χ = 2."""
    V, F = mesh.octahedron()
    triangles = np.concatenate([np.asarray(V)[np.asarray(F)], [[[0, 0, 0], [0.5, 0, 0], [1, 0, 0]]]])
    V1, F1 = mesh.read(_write(tmp_path, "o.stl", _binary_stl(triangles)))
    assert V1.shape == (8, 3) and F1.shape == (9, 3)
    V2, F2, dropped = mesh.drop_degenerate_faces(V1, F1)
    V3, F3, removed = mesh.remove_unreferenced_vertices(V2, F2)
    assert dropped.faces == (8,) and removed.count == 2 and V3.shape == (6, 3)
    assert mesh.euler_characteristic(F3) == 2
