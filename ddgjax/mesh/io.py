"""Reading and writing surface meshes: OBJ, OFF, PLY, STL, legacy VTK and the other formats of meshio.

OBJ, OFF and STL are parsed here (OBJ texture and normal indices `f 1/1/1`, negative relative
indices, faces of any number of corners); PLY and legacy VTK are read by meshio.  Every count in a
header is checked against the size of the file before anything is allocated: n items that take at
least b bytes each need n b bytes, so a hostile header cannot make a reader allocate more than
the file justifies.  Every failure is a `MeshFileError` naming the file and what is wrong,
whatever the reader raised (meshio may even call `sys.exit`).
"""

from __future__ import annotations

import contextlib
import io
import os
import re
from pathlib import Path

import numpy as np

from ..errors import MeshFileError
from .connectivity import faces_as_corners

__all__ = ["read", "write"]

_CELL_TYPES = {3: "triangle", 4: "quad"}
_LINE_LIMIT = 1 << 16  # the longest header line read; a header line is a few words


def read(path):
    """`(V, F)` from a mesh file: V (nv, 3) float64; F an (nf, k) int64 array when all faces have
    k corners, else a list of polygons (vertex index lists) in the order of the file.  Non-surface
    cells (lines, points) are ignored.  The format is chosen by the extension.

    **Raises:** `MeshFileError` naming the file when it cannot be opened, is malformed or
    truncated, its header promises more data than the file holds, a coordinate is NaN or infinite
    (naming the vertex), a face refers to a vertex that is not there or has fewer than 3 corners
    (naming the face), or it holds no triangles, quads or polygons.
    """
    path = Path(path)
    size = _file_size(path)
    reader = _READERS.get(path.suffix.lower(), _read_meshio)
    try:
        V, sizes, corners = reader(path, size)
    except (MeshFileError, KeyboardInterrupt):
        raise
    except BaseException as error:  # noqa: BLE001 -- also SystemExit, which meshio raises on a failed read
        raise MeshFileError(path, f"cannot be read as {_format_name(path)}: {_describe(error)}") from error
    return _surface(path, V, sizes, corners)


def write(path, V, F) -> None:
    """Write `(V, F)` to `path`, format from the extension; faces are grouped by corner count into
    meshio cell blocks ("triangle", "quad", "polygon").  Face order is kept within each size.
    OFF is written here, with faces of any number of corners (meshio's writer drops all but
    triangles).
    """
    vertex, face, _ = faces_as_corners(F)
    sizes = np.bincount(face)
    if Path(path).suffix.lower() == ".off":
        _write_off(path, np.asarray(V, dtype=np.float64), sizes, vertex)
    else:
        _write_meshio(path, np.asarray(V, dtype=np.float64), sizes, vertex)


def _write_meshio(path, V, sizes, vertex) -> None:
    import meshio

    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    cells = []
    for k in np.unique(sizes):
        rows = starts[sizes == k][:, None] + np.arange(k)[None]
        cells.append((_CELL_TYPES.get(int(k), "polygon"), vertex[rows]))
    meshio.write(path, meshio.Mesh(V, cells))


# --- the surface a reader found ----------------------------------------------------------------


def _surface(path, V, sizes, corners):
    """`(V, F)` from the vertices and the faces as corner counts `sizes` (nf,) and vertex indices
    `corners` (sum(sizes),); raises `MeshFileError` for a non-finite coordinate, an index out of
    range, a face of fewer than 3 corners, or no face at all."""
    V = np.asarray(V, dtype=np.float64)
    if V.ndim != 2 or V.shape[1] not in (2, 3):
        raise MeshFileError(path, f"vertices must have 2 or 3 coordinates, got an array of shape {V.shape}")
    if V.shape[1] == 2:
        V = np.hstack([V, np.zeros((V.shape[0], 1))])
    bad = np.flatnonzero(~np.all(np.isfinite(V), axis=1))
    if bad.size:
        raise MeshFileError(path, f"vertex {bad[0]} has the non-finite coordinates {V[bad[0]].tolist()} "
                                  f"({bad.size} of {len(V)} vertices are not finite)")
    if sizes.size == 0:
        raise MeshFileError(path, "contains no surface cells (triangles, quads or polygons)")
    short = np.flatnonzero(sizes < 3)
    if short.size:
        raise MeshFileError(path, f"face {short[0]} has {sizes[short[0]]} corners; a face needs at least 3")
    out = np.flatnonzero((corners < 0) | (corners >= len(V)))
    if out.size:
        face = int(np.searchsorted(np.cumsum(sizes), out[0], side="right"))
        raise MeshFileError(path, f"face {face} refers to vertex {corners[out[0]]} (0-based), but the file has "
                                  f"{len(V)} vertices")
    if np.all(sizes == sizes[0]):
        return V, corners.reshape(-1, int(sizes[0]))
    return V, [f.tolist() for f in np.split(corners, np.cumsum(sizes)[:-1])]


def _corners(faces) -> tuple[np.ndarray, np.ndarray]:
    """`(sizes, corners)` of a list of faces (each a sequence of vertex indices)."""
    sizes = np.array([len(f) for f in faces], dtype=np.int64)
    corners = np.fromiter((i for f in faces for i in f), dtype=np.int64, count=int(sizes.sum()))
    return sizes, corners


# --- files ---------------------------------------------------------------------------------


def _file_size(path: Path) -> int:
    """The size of the regular, readable file `path` in bytes, else `MeshFileError`."""
    if not path.exists():
        raise MeshFileError(path, "no such file")
    if not path.is_file():
        raise MeshFileError(path, "is not a regular file")
    if not os.access(path, os.R_OK):
        raise MeshFileError(path, "is not readable (permission denied)")
    return path.stat().st_size


def _format_name(path: Path) -> str:
    return path.suffix[1:].upper() or "a mesh (no extension)"


def _describe(error: BaseException) -> str:
    """One line for an exception raised inside a reader."""
    if isinstance(error, SystemExit):
        return "the reader gave up (it called sys.exit)"
    message = " ".join(str(error).split())
    return f"{type(error).__name__}: {message}" if message else type(error).__name__


def _text(path: Path) -> str:
    """The contents of a text mesh file; a file with NUL bytes is binary, not text."""
    data = path.read_bytes()
    nul = data.find(bytes(1))
    if nul >= 0:
        raise MeshFileError(path, f"is a binary file (a NUL byte at offset {nul}), not a text {_format_name(path)} file")
    return data.decode("utf-8", errors="replace")


def _lines(text: str):
    """`(line number, words)` of each non-empty line, comments (`#` to the end of the line) removed
    and lines ending in a backslash joined to the next."""
    pending, start = "", 0
    for number, line in enumerate(text.splitlines(), start=1):
        line = line.split("#", 1)[0]
        if line.rstrip().endswith("\\"):
            pending, start = pending + line.rstrip()[:-1] + " ", start or number
            continue
        words = (pending + line).split()
        if words:
            yield start or number, words
        pending, start = "", 0


def _require(path, what: str, needed: int, size: int) -> None:
    """Raise unless `needed` bytes, the least that the header's `what` take, fit in `size`."""
    if needed > size:
        raise MeshFileError(path, f"the header promises {what}, which take at least {needed} bytes, but the file "
                                  f"has only {size} bytes (truncated or corrupt)")


def _floats(path, where: str, words: list[str], what: str) -> list[float]:
    """The numbers `words` of `what` (a vertex) found at `where` ("line 7: ", or "")."""
    try:
        return [float(w) for w in words]
    except ValueError:
        raise MeshFileError(path, f"{where}{what} {' '.join(words)!r} is not a list of numbers") from None


def _int(path, number: int, word: str, what: str) -> int:
    try:
        return int(word)
    except ValueError:
        raise MeshFileError(path, f"line {number}: {what} {word!r} is not an integer") from None


# --- OBJ -------------------------------------------------------------------------------------


def _read_obj(path: Path, size: int):
    """Wavefront OBJ: `v x y z [w]` vertices and `f` faces whose corners are `v`, `v/vt`, `v/vt/vn`
    or `v//vn`, with 1-based indices or negative ones relative to the last vertex; every other
    statement (vt, vn, l, g, o, s, usemtl, ...) is skipped."""
    vertices, faces = [], []
    for number, words in _lines(_text(path)):
        if words[0] == "v":
            if len(words) < 4:
                raise MeshFileError(path, f"line {number}: vertex {len(vertices)} has {len(words) - 1} coordinates, "
                                          "needs 3")
            vertices.append(_floats(path, f"line {number}: ", words[1:4], f"vertex {len(vertices)}"))
        elif words[0] == "f":
            faces.append([_obj_index(path, number, w, len(vertices)) for w in words[1:]])
    sizes, corners = _corners(faces)
    return np.array(vertices, dtype=np.float64).reshape(-1, 3), sizes, corners


def _obj_index(path, number: int, word: str, n_before: int) -> int:
    """The 0-based vertex of an OBJ face corner `v[/vt[/vn]]`; a negative `v` counts back from the
    last of the `n_before` vertices defined so far."""
    i = _int(path, number, word.split("/", 1)[0], "the face corner")
    if i == 0 or -i > n_before:
        raise MeshFileError(path, f"line {number}: the face corner {word!r} refers to no vertex "
                                  f"({n_before} vertices precede it; OBJ indices start at 1, or count back from -1)")
    return i - 1 if i > 0 else n_before + i


# --- OFF -------------------------------------------------------------------------------------


def _read_off(path: Path, size: int):
    """Geomview OFF (also COFF, NOFF, STOFF ...): `OFF`, `nv nf ne`, nv lines `x y z ...`, nf lines
    `k i_1 ... i_k ...` (0-based; colours after the indices are skipped)."""
    lines = _lines(_text(path))
    number, words = next(lines, (1, [""]))
    keyword, words = words[0], words[1:]
    if not re.fullmatch(r"(ST)?C?N?OFF", keyword):
        raise MeshFileError(path, f"line {number}: expected the keyword OFF (or COFF, NOFF, STOFF), got {keyword!r}"
                                  + ("; binary, 4-D and n-D OFF are not supported" if keyword.endswith("OFF") else ""))
    if words[:1] == ["BINARY"]:
        raise MeshFileError(path, "binary OFF is not supported")
    if not words:
        number, words = next(lines, (number + 1, []))
    if len(words) < 2:
        raise MeshFileError(path, f"line {number}: expected the counts 'vertices faces edges', got {' '.join(words)!r}")
    nv, nf = (_int(path, number, w, "the count") for w in words[:2])
    if nv < 0 or nf < 0:
        raise MeshFileError(path, f"line {number}: negative counts {nv} vertices, {nf} faces")
    _require(path, f"{nv} vertices and {nf} faces", 2 * (3 * nv + 4 * nf) - 1, size)  # a number and a space each
    V = [_off_vertex(path, next(lines, None), k, nv) for k in range(nv)]
    faces = [_off_face(path, next(lines, None), f, nf) for f in range(nf)]
    extra = next(lines, None)
    if extra is not None:
        raise MeshFileError(path, f"line {extra[0]}: more data after the {nv} vertices and {nf} faces of the header")
    sizes, corners = _corners(faces)
    return np.array(V, dtype=np.float64).reshape(-1, 3), sizes, corners


def _off_vertex(path, line, k: int, nv: int) -> list[float]:
    if line is None:
        raise MeshFileError(path, f"the file ends after {k} of its {nv} vertices (truncated)")
    number, words = line
    if len(words) < 3:
        raise MeshFileError(path, f"line {number}: vertex {k} has {len(words)} coordinates, needs 3")
    return _floats(path, f"line {number}: ", words[:3], f"vertex {k}")


def _off_face(path, line, f: int, nf: int) -> list[int]:
    if line is None:
        raise MeshFileError(path, f"the file ends after {f} of its {nf} faces (truncated)")
    number, words = line
    k = _int(path, number, words[0], f"the corner count of face {f}")
    if k < 0 or len(words) < k + 1:
        raise MeshFileError(path, f"line {number}: face {f} announces {k} corners but lists {len(words) - 1} numbers")
    return [_int(path, number, w, f"a vertex of face {f}") for w in words[1:k + 1]]


# --- PLY, STL, VTK ----------------------------------------------------------------------------


_PLY_BYTES = {"char": 1, "uchar": 1, "int8": 1, "uint8": 1, "short": 2, "ushort": 2, "int16": 2, "uint16": 2,
              "int": 4, "uint": 4, "int32": 4, "uint32": 4, "float": 4, "float32": 4, "int64": 8, "uint64": 8,
              "double": 8, "float64": 8}


def _read_ply(path: Path, size: int):
    """PLY, ascii or binary: the header's element counts are checked against the file size (an
    ascii property takes at least 2 bytes, a binary one its type's size, a list its count), then
    meshio reads the data."""
    with open(path, "rb") as f:
        elements, binary = _ply_header(path, f)
        size -= f.tell()
    needed = sum(count * sum(2 if not binary else _PLY_BYTES[t] for t, _ in properties)
                 for _, count, properties in elements)
    _require(path, ", ".join(f"{count} {name}" for name, count, _ in elements), needed - (not binary), size)
    names = {element: [name for _, name in properties] for element, _, properties in elements}
    if not {"x", "y", "z"} <= set(names.get("vertex", [])):
        raise MeshFileError(path, f"the PLY header has no element 'vertex' with properties x, y, z (has {names})")
    if "vertex_indices" not in names.get("face", []):
        raise MeshFileError(path, f"the PLY header has no element 'face' with the list 'vertex_indices' (has {names})")
    import meshio.ply

    return _meshio_cells(meshio.ply.read(str(path)))


def _ply_header(path, f) -> tuple[list[tuple[str, int, list[tuple[str, str]]]], bool]:
    """`([(element, count, [(type, name) of each property; for a list the type of its count])],
    binary)`."""
    if _header_line(path, f) != "ply":
        raise MeshFileError(path, "does not start with the line 'ply'")
    elements, binary = [], None
    for line in iter(lambda: _header_line(path, f), "end_header"):
        words = line.split()
        if not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "format" and words[2:] == ["1.0"] and words[1] in ("ascii", "binary_little_endian",
                                                                          "binary_big_endian"):
            binary = words[1] != "ascii"
        elif words[0] == "element" and len(words) == 3 and re.fullmatch(r"\d+", words[2]):
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property" and elements and _ply_property_type(words):
            elements[-1][2].append((_ply_property_type(words), words[-1]))
        else:
            raise MeshFileError(path, f"unexpected PLY header line {line!r}")
    if binary is None:
        raise MeshFileError(path, "the PLY header has no 'format' line")
    return elements, binary


def _ply_property_type(words: list[str]) -> str | None:
    """The type of `property TYPE NAME`, or the count type of `property list COUNT ITEM NAME`;
    None for a malformed property line."""
    if len(words) == 3 and words[1] in _PLY_BYTES:
        return words[1]
    if len(words) == 5 and words[1] == "list" and words[2] in _PLY_BYTES and words[3] in _PLY_BYTES:
        return words[2]
    return None


def _header_line(path, f) -> str:
    line = f.readline(_LINE_LIMIT)
    if not line:
        raise MeshFileError(path, "the file ends inside its header (truncated)")
    if len(line) == _LINE_LIMIT:
        raise MeshFileError(path, f"a header line is longer than {_LINE_LIMIT} bytes (not a header)")
    return line.decode("ascii", errors="replace").strip()


_STL_TRIANGLE = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])


def _read_stl(path: Path, size: int):
    """STL: binary (an 80-byte header, the triangle count, 50 bytes a triangle) when the count
    matches the size, else ascii (`solid`, `facet`, `outer loop`, three `vertex x y z`, ...).
    Corners that coincide exactly become one vertex, numbered in order of first appearance."""
    with open(path, "rb") as f:
        head = f.read(84)
    count = int.from_bytes(head[80:84], "little") if len(head) == 84 else None
    if count is not None and 84 + 50 * count == size:
        corners = np.fromfile(path, dtype=_STL_TRIANGLE, offset=84)["corners"]
    elif head.lstrip().startswith(b"solid"):
        corners = _stl_ascii_corners(path)
    elif count is None:
        raise MeshFileError(path, f"has {size} bytes: neither an ascii STL ('solid ...') nor a binary one (84 bytes at least)")
    else:
        _require(path, f"{count} binary triangles", 84 + 50 * count, size)
        raise MeshFileError(path, f"a binary STL of {count} triangles has {84 + 50 * count} bytes, this file {size}")
    V, inverse = _unique_rows(corners.reshape(-1, 3).astype(np.float64))
    return V, np.full(len(corners), 3, dtype=np.int64), inverse


def _stl_ascii_corners(path: Path) -> np.ndarray:
    """The (nf, 3, 3) corners of the facets of an ascii STL file, three `vertex` lines a loop."""
    text = _text(path)
    loops = re.findall(r"outer\s+loop(.*?)endloop", text, flags=re.S)
    vertices = re.findall(r"vertex\s+(\S+)\s+(\S+)\s+(\S+)", text)
    if len(vertices) != 3 * len(loops):
        counts = [len(re.findall(r"vertex\s", loop)) for loop in loops]
        bad = next((f for f, c in enumerate(counts) if c != 3), None)
        if bad is None:
            raise MeshFileError(path, f"the file ends inside facet {len(loops)} (no 'endloop': truncated)")
        raise MeshFileError(path, f"facet {bad} has {counts[bad]} vertices, an STL facet has 3")
    try:
        return np.array(vertices, dtype=np.float64).reshape(-1, 3, 3)
    except ValueError:
        k = next(k for k, v in enumerate(vertices) if not _is_number_row(v))
        raise MeshFileError(path, f"vertex {k % 3} of facet {k // 3} {' '.join(vertices[k])!r} is not a list of "
                                  "numbers") from None


def _is_number_row(words) -> bool:
    try:
        return bool([float(w) for w in words])
    except ValueError:
        return False


def _unique_rows(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`(U, inverse)` with `U[inverse] == P`: the distinct rows of P in order of first appearance."""
    _, first, inverse = np.unique(P, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    return P[first[order]], rank[inverse.reshape(-1)]


_VTK_BYTES = {"bit": 1, "unsigned_char": 1, "char": 1, "unsigned_short": 2, "short": 2, "unsigned_int": 4,
              "int": 4, "unsigned_long": 8, "long": 8, "float": 4, "double": 8, "vtktypeint64": 8,
              "vtktypeuint64": 8, "vtkidtype": 4}
_VTK_DATASETS = ("UNSTRUCTURED_GRID", "POLYDATA")  # structured grids make points from DIMENSIONS alone


def _read_vtk(path: Path, size: int):
    """Legacy VTK, an UNSTRUCTURED_GRID or POLYDATA: every count in a section line is checked
    against the file size (an ascii number takes at least 2 bytes, a binary one its type's size),
    then meshio reads an unstructured grid and `_read_polydata` the polygons of a POLYDATA."""
    dataset = None
    with open(path, "rb") as f:
        if not _header_line(path, f).startswith("# vtk DataFile Version"):
            raise MeshFileError(path, "does not start with '# vtk DataFile Version'")
        _header_line(path, f)  # the title
        encoding = _header_line(path, f).upper()
        if encoding not in ("ASCII", "BINARY"):
            raise MeshFileError(path, f"the third line must be ASCII or BINARY, got {encoding!r}")
        per_item = 0
        for raw in f:
            if raw[:1].isalpha():  # data lines start with a digit, a sign or a binary byte
                words = raw[:_LINE_LIMIT].decode("ascii", errors="replace").split()
                per_item = _vtk_section(path, words, per_item, encoding == "BINARY", size)
                dataset = words[1] if words[0] == "DATASET" and len(words) > 1 else dataset
    if dataset == "POLYDATA":
        return _read_polydata(path, encoding == "BINARY")
    import meshio.vtk

    return _meshio_cells(meshio.vtk.read(str(path)))


def _vtk_array(path, data: bytes, start: int, count: int, type_name: str, binary: bool) -> tuple[np.ndarray, int]:
    """`(values, end)`: `count` numbers of the VTK type `type_name` from `data[start:]` (binary:
    big-endian, as legacy VTK writes them; ascii: whitespace-separated)."""
    if binary:
        kind = "f" if type_name in ("float", "double") else ("u" if type_name.startswith("unsigned") else "i")
        width = _VTK_BYTES.get(type_name, 4)
        end = start + count * width
        if end > len(data):
            raise MeshFileError(path, f"the file ends inside {count} {type_name} numbers (truncated)")
        return np.frombuffer(data[start:end], dtype=f">{kind}{width}").astype(np.float64 if kind == "f" else np.int64), end
    words = data[start:].split(maxsplit=count)
    if len(words) < count:
        raise MeshFileError(path, f"the file ends inside {count} {type_name} numbers (truncated)")
    try:
        values = np.array(words[:count], dtype=np.float64)
    except ValueError:
        raise MeshFileError(path, f"a {type_name} number of a section is not a number") from None
    return values, len(data) - (len(words[count]) if len(words) > count else 0)


def _vtk_section_at(data: bytes, key: bytes) -> re.Match | None:
    return re.search(rb"(?m)^" + key + rb"[ \t]+([^\r\n]*)\r?\n", data)


def _read_polydata(path: Path, binary: bool):
    """`(points, sizes, corners)` of a legacy VTK POLYDATA: the POINTS and the POLYGONS, in the
    classic layout (`POLYGONS n size`, then per polygon its corner count and corners) or the
    layout of VTK 5.1 (`POLYGONS n_offsets n_connectivity`, then OFFSETS and CONNECTIVITY)."""
    data = path.read_bytes()
    points = _vtk_section_at(data, b"POINTS")
    if points is None:
        raise MeshFileError(path, "the POLYDATA has no POINTS section")
    n, type_name = points.group(1).decode("ascii", errors="replace").split()[:2]
    P, _ = _vtk_array(path, data, points.end(), 3 * int(n), type_name.lower(), binary)
    polygons = _vtk_section_at(data, b"POLYGONS")
    if polygons is None:
        return P.reshape(-1, 3), np.zeros(0, np.int64), np.zeros(0, np.int64)
    first, second = (int(w) for w in polygons.group(1).split()[:2])
    offsets = _vtk_section_at(data[polygons.end():], b"OFFSETS")
    if offsets is not None:  # VTK 5.1: offsets (n + 1) and connectivity
        start = polygons.end() + offsets.end()
        O, end = _vtk_array(path, data, start, first, offsets.group(1).decode().split()[0].lower(), binary)
        connectivity = _vtk_section_at(data[end:], b"CONNECTIVITY")
        if connectivity is None:
            raise MeshFileError(path, "the POLYGONS have OFFSETS but no CONNECTIVITY")
        C, _ = _vtk_array(path, data, end + connectivity.end(), second,
                          connectivity.group(1).decode().split()[0].lower(), binary)
        return P.reshape(-1, 3), np.diff(O.astype(np.int64)), C.astype(np.int64)
    L, _ = _vtk_array(path, data, polygons.end(), second, "int", binary)
    L = L.astype(np.int64)
    sizes, heads, k = [], [], 0
    while k < len(L):
        sizes.append(int(L[k]))
        heads.append(k)
        k += 1 + int(L[k])
    if k != len(L) or len(sizes) != first or min(sizes, default=1) < 0:
        raise MeshFileError(path, f"the POLYGONS section promises {first} polygons in {second} numbers, which do not "
                                  "add up (corrupt)")
    corners = np.concatenate([L[h + 1:h + 1 + m] for h, m in zip(heads, sizes)] or [np.zeros(0, np.int64)])
    return P.reshape(-1, 3), np.array(sizes, dtype=np.int64), corners


_VTK_COUNTED = ("CELLS", "POLYGONS", "TRIANGLE_STRIPS", "LINES", "VERTICES", "CELL_TYPES", "POINT_DATA", "CELL_DATA",
                "X_COORDINATES", "Y_COORDINATES", "Z_COORDINATES")  # a count, at least that many numbers
_VTK_PER_ITEM = ("SCALARS", "COLOR_SCALARS", "TEXTURE_COORDINATES")  # per item: the section's count, or 1


def _vtk_numbers(words: list[str], counts: list[int], per_item: int) -> int:
    """The least number of numbers a section line of a legacy VTK file promises; `per_item` is the
    count of the current POINT_DATA or CELL_DATA."""
    key = words[0]
    if key == "POINTS":
        return 3 * counts[0] if counts else 0
    if key in _VTK_COUNTED:
        return max(counts, default=0)
    if key in _VTK_PER_ITEM:
        return per_item * (counts[0] if counts else 1)
    if key in ("VECTORS", "NORMALS", "TENSORS"):
        return (9 if key == "TENSORS" else 3) * per_item
    if key == "LOOKUP_TABLE":
        return 4 * max(counts, default=0)
    if len(words) == 4 and len(counts) == 2 and words[3].lower() in _VTK_BYTES:  # a FIELD array: name ncomp ntuples type
        return counts[0] * counts[1]
    return 0


def _vtk_section(path, words: list[str], per_item: int, binary: bool, size: int) -> int:
    """Check one section line of a legacy VTK file against the file size (an ascii number takes
    at least 2 bytes, a binary one its type's size); returns the count of the current POINT_DATA
    or CELL_DATA (the length of the attribute arrays that follow)."""
    counts = [int(w) for w in words[1:] if re.fullmatch(r"-?\d+", w)]
    if words[0] == "DATASET" and not set(words[1:2]) & set(_VTK_DATASETS):
        raise MeshFileError(path, f"holds the data set {' '.join(words[1:2])!r}; only {' and '.join(_VTK_DATASETS)} "
                                  "are read (write the surface as an unstructured grid or polydata)")
    if any(c < 0 for c in counts):
        raise MeshFileError(path, f"negative count in the line {' '.join(words)!r}")
    numbers = _vtk_numbers(words, counts, per_item)
    width = next((_VTK_BYTES[w.lower()] for w in words[1:] if w.lower() in _VTK_BYTES), 1) if binary else 2
    _require(path, f"{numbers} numbers in the section {' '.join(words)!r}", numbers * width - (not binary), size)
    return max(counts, default=0) if words[0] in ("POINT_DATA", "CELL_DATA") else per_item


def _read_meshio(path: Path, size: int):
    """Any other format meshio knows, by the extension; meshio's messages become the error's."""
    import meshio

    printed = io.StringIO()
    try:
        with contextlib.redirect_stdout(printed), contextlib.redirect_stderr(printed):
            mesh = meshio.read(path)
    except SystemExit:
        raise MeshFileError(path, " ".join(printed.getvalue().split()) or "meshio cannot read it") from None
    return _meshio_cells(mesh)


def _meshio_cells(mesh):
    """`(points, sizes, corners)` of the surface cells of a meshio mesh, in the order of the file."""
    blocks = [np.asarray(c.data, dtype=np.int64) for c in mesh.cells
              if c.type in ("triangle", "quad") or c.type.startswith("polygon")]
    sizes = np.concatenate([np.full(len(b), b.shape[1], dtype=np.int64) for b in blocks] or [np.zeros(0, np.int64)])
    corners = np.concatenate([b.reshape(-1) for b in blocks] or [np.zeros(0, np.int64)])
    return mesh.points, sizes, corners


_READERS = {".obj": _read_obj, ".off": _read_off, ".ply": _read_ply, ".stl": _read_stl, ".vtk": _read_vtk}


def _write_off(path, V, sizes, vertex) -> None:
    """OFF with faces of any number of corners: `OFF`, `nv nf 0`, the vertices, `k i_1 ... i_k`."""
    rows = np.split(vertex, np.cumsum(sizes)[:-1])
    with open(path, "w", encoding="ascii") as f:
        f.write(f"OFF\n{len(V)} {len(rows)} 0\n")
        f.writelines(f"{x!r} {y!r} {z!r}\n" for x, y, z in V.tolist())
        f.writelines(f"{len(r)} {' '.join(map(str, r.tolist()))}\n" for r in rows)
