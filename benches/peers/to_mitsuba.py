#!/usr/bin/env python3
"""Convert a tracer scene (JSON, format version 1 or 2) into a Mitsuba 3 scene.

What both renderers support is converted; anything else is refused with a
message naming the key (exception `Unsupported`, exit status 2 from the
command line). The geometry is built exactly as tracer builds it
(src/geometry/shapes.rs, src/geometry/transform.rs, src/scene/builder.rs):
the same triangles, in world space, with the same winding, handed to
Mitsuba as `mi.Mesh` objects built from numpy arrays (no files written).

Conversions (tracer -> Mitsuba 3):

- camera `perspective` -> `perspective`, `fov_axis: 'y'`, `to_world =
  look_at(position, look_at, up)`. Both put `forward x up` on the image's
  right and pixel (0, 0) at the top left (checked by rendering: see
  compare.py's agreement check).
- `aperture_radius` > 0 (format 2) -> `thinlens` with `aperture_radius` and
  `focus_distance` (both measure the plane in focus along the view axis).
- film -> `hdrfilm` (width x height, `pixel_format: rgb`) with a box filter
  one pixel wide (tracer's samples are uniform in their pixel).
- `diffuse` (constant albedo) -> `twosided(diffuse)`: tracer's diffuse
  reflects on both faces, Mitsuba's only on the front.
- `mirror` -> `twosided(conductor)` with `material: none` (Fresnel = 1) and
  `specular_reflectance` = reflectance.
- `dielectric` -> `dielectric`, `int_ior` = ior, `ext_ior` = 1,
  `specular_transmittance` = transmittance (applied at every refraction in
  both; reflection untinted in both; radiance scaled by 1/eta^2 on
  refraction in both). tracer tells inside from outside by the geometric
  normal, Mitsuba by the shading normal: they differ only on smooth-normal
  meshes, at grazing angles.
- `conductor` (format 2) -> `twosided(roughconductor)` with `distribution:
  ggx`, `alpha`, `eta`/`k` (or `material: none`, Fresnel 1, when both are
  absent) and `specular_reflectance`; `alpha` 0 -> `twosided(conductor)`.
- `rough_dielectric` (format 2) -> `roughdielectric` with `distribution:
  ggx`, `alpha`, `int_ior`, `ext_ior` 1, `specular_transmittance`; `alpha`
  0 -> `dielectric`.
- `plastic` (format 2) -> `twosided(roughplastic)` with `distribution:
  ggx`, `alpha`, `int_ior` = ior, `ext_ior` 1, `diffuse_reflectance` =
  albedo, `nonlinear` false; `alpha` 0 -> `twosided(plastic)`.
- objects `triangles`, `quad`, `cube`, `sphere` (tracer's icosphere, vertex
  for vertex) and `mesh` (an OBJ file read as tracer reads it, see
  `read_obj`) with their `transform` -> `mi.Mesh`; zero-area triangles are
  dropped as tracer drops them; vertex normals are carried by the inverse
  transpose and, as in tracer, ignored on a triangle where one is zero, and
  turned to the side of the geometric normal.
- `emission` -> an `area` emitter with `radiance`: both emit from the front
  face only (tracer: the counter-clockwise side; Mitsuba: the side of the
  normal, which for a mesh without vertex normals is
  cross(p1 - p0, p2 - p0), the same side).
- lights `point` -> `point` (`intensity`), `directional` -> `directional`
  (`irradiance`, `direction`), `environment` (format 2) -> `constant`
  (`radiance` x `scale`) or `envmap` (`filename`, `scale`, `to_world` =
  the rotation): Mitsuba's envmap is the mapping tracer's is defined by.
- `render.max_depth` -> `max_depth`: both count path segments (1: emitters
  seen directly, 2: direct lighting).

Refused: `mesh` objects whose OBJ file uses MTL materials and that name no
`material` of their own, textures, `two_sided` emitters (Mitsuba 3's
area light is one-sided), emitters with vertex normals (Mitsuba emits on the
side of the interpolated normal, tracer of the geometric one), `spot` lights
(different falloff curves), `.trs` files, format versions other than 1 and 2,
and any key this converter does not know.

Usage as a module (a Mitsuba variant must be set first):

    import mitsuba as mi; mi.set_variant('llvm_ad_rgb')
    import to_mitsuba
    scene = mi.load_dict(to_mitsuba.convert('scenes/cornell-box.json', spp=64))

From the command line: `to_mitsuba.py SCENE [--spp N] [-o OUT.exr]` converts
and describes the scene, and with `-o` renders it with Mitsuba's `path`.
"""

import argparse
import json
import math
import os
import sys

import numpy as np

FORMAT_VERSIONS = (1, 2)


class Unsupported(Exception):
    """The scene uses something this converter cannot express in Mitsuba 3."""


def _fail(key, message):
    raise Unsupported(f"{key}: {message}")


def _keys(obj, key, allowed):
    if not isinstance(obj, dict):
        _fail(key, f"expected an object, found {type(obj).__name__}")
    for k in obj:
        if k not in allowed:
            _fail(f"{key}.{k}" if key else k,
                  f"not converted (known keys: {', '.join(sorted(allowed))})")


def _vec3(v, key):
    a = np.asarray(v, dtype=np.float64)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        _fail(key, f"expected [x, y, z], found {v!r}")
    return a


def _color(v, key):
    c = _vec3(v, key)
    if np.any(c < 0):
        _fail(key, f"negative colour {v!r}")
    return [float(x) for x in c]


# ---------------------------------------------------------------- geometry

def quad():
    """tracer's unit quad: xz-plane, centred, facing +y (shapes.rs)."""
    p = np.array([[-0.5, 0, -0.5], [-0.5, 0, 0.5], [0.5, 0, 0.5], [0.5, 0, -0.5]], float)
    return p, None, np.array([0, 1, 2, 0, 2, 3], np.int64)


def cube():
    """tracer's unit cube: 12 triangles, faces outwards (shapes.rs)."""
    X, Y, Z = np.eye(3)
    faces = [(X, Y, Z), (-X, Z, Y), (Y, Z, X), (-Y, X, Z), (Z, X, Y), (-Z, Y, X)]
    pos, idx = [], []
    for n, a, b in faces:
        base = len(pos)
        for s, t in [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)]:
            pos.append(0.5 * n + s * a + t * b)
        idx += [base, base + 1, base + 2, base, base + 2, base + 3]
    return np.array(pos), None, np.array(idx, np.int64)


def sphere(center, radius, level):
    """tracer's icosphere (shapes.rs): same vertices, faces and winding.

    The UV seam copies tracer adds are duplicates of existing vertices, so
    they change neither the geometry nor the normals and are left out.
    """
    t = (1.0 + math.sqrt(5.0)) / 2.0
    dirs = [np.array(d, float) for d in [
        (-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
        (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]]
    dirs = [d / np.linalg.norm(d) for d in dirs]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9),
             (5, 11, 4), (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2),
             (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
             (8, 6, 7), (9, 8, 1)]
    for _ in range(level):
        mid = {}

        def midpoint(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                d = dirs[a] + dirs[b]
                dirs.append(d / np.linalg.norm(d))
                mid[key] = len(dirs) - 1
            return mid[key]

        nxt = []
        for a, b, c in faces:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            nxt += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = nxt
    d = np.array(dirs)
    return center + radius * d, d, np.array(faces, np.int64).ravel()


def _rotation(axis, degrees):
    """glam's Mat3::from_axis_angle (right-hand rule), axis normalised."""
    x, y, z = axis / np.linalg.norm(axis)
    a = math.radians(degrees)
    s, c = math.sin(a), math.cos(a)
    C = 1.0 - c
    return np.array([
        [x * x * C + c, x * y * C - z * s, x * z * C + y * s],
        [y * x * C + z * s, y * y * C + c, y * z * C - x * s],
        [z * x * C - y * s, z * y * C + x * s, z * z * C + c]])


def transform_matrix(t, key):
    """The 4x4 object-to-world matrix of an object's `transform` (transform.rs)."""
    if t is None:
        return np.eye(4)
    _keys(t, key, {"matrix", "scale", "rotate", "translate"})
    if "matrix" in t:
        if len(t) > 1:
            _fail(key, "give either matrix or scale/rotate/translate")
        m = np.asarray(t["matrix"], float)
        if m.shape != (16,):
            _fail(f"{key}.matrix", "expected 16 numbers")
        m = m.reshape(4, 4)  # row-major: the translation is the fourth column
        if not np.array_equal(m[3], [0, 0, 0, 1]):
            _fail(f"{key}.matrix", "not affine")
    else:
        s = t.get("scale", 1.0)
        s = np.full(3, float(s)) if np.isscalar(s) else _vec3(s, f"{key}.scale")
        r = np.eye(3)
        if "rotate" in t:
            rot = np.asarray(t["rotate"], float)
            if rot.shape != (4,) or not np.any(rot[:3]):
                _fail(f"{key}.rotate", "expected [axis_x, axis_y, axis_z, degrees]")
            r = _rotation(rot[:3], rot[3])
        m = np.eye(4)
        m[:3, :3] = r @ np.diag(s)  # scale, then rotate, then translate
        m[:3, 3] = _vec3(t.get("translate", [0, 0, 0]), f"{key}.translate")
    if abs(np.linalg.det(m[:3, :3])) < 1e-12:
        _fail(key, "singular transform")
    return m


def world_mesh(positions, normals, indices, m):
    """Transform to world space and drop zero-area triangles, as tracer does.

    Returns (positions, normals or None, faces (F, 3), face_has_normals (F,)).
    """
    # tracer transforms in f32 and tests the area in f64 of those f32 values.
    p = (positions @ m[:3, :3].T + m[:3, 3]).astype(np.float32)
    n = None
    if normals is not None:
        nm = np.linalg.inv(m[:3, :3]).T
        n = normals @ nm.T
        length = np.linalg.norm(n, axis=1, keepdims=True)
        n = np.where(length > 0, n / np.where(length > 0, length, 1), 0.0)
    f = indices.reshape(-1, 3)
    pd = p.astype(np.float64)
    e1, e2 = pd[f[:, 1]] - pd[f[:, 0]], pd[f[:, 2]] - pd[f[:, 0]]
    area = np.linalg.norm(np.cross(e1, e2), axis=1)
    keep = (area > 0) & np.all(np.isfinite(pd[f]).reshape(len(f), -1), axis=1)
    f = f[keep]
    has_n = np.zeros(len(f), bool)
    if n is not None:
        has_n = np.all(np.linalg.norm(n[f], axis=2) > 0, axis=1)
    return p, n, f, has_n


# ------------------------------------------------------------ mitsuba parts

# tracer treats narrower GGX lobes as smooth (src/material/microfacet.rs).
SMOOTH_ALPHA = 1e-4


def _rgb(c):
    return {"type": "rgb", "value": [float(x) for x in c]}


def bsdf_dict(mat, key):
    if not isinstance(mat, dict) or "type" not in mat:
        _fail(f"{key}.type", "missing")
    kind = mat["type"]
    if kind == "diffuse":
        _keys(mat, key, {"type", "albedo"})
        albedo = mat.get("albedo", [0.5, 0.5, 0.5])
        if isinstance(albedo, dict):
            _fail(f"{key}.albedo", "textures are not converted")
        return {"type": "twosided",
                "bsdf": {"type": "diffuse", "reflectance": _rgb(_color(albedo, f"{key}.albedo"))}}
    if kind == "mirror":
        _keys(mat, key, {"type", "reflectance"})
        r = _color(mat.get("reflectance", [1, 1, 1]), f"{key}.reflectance")
        return {"type": "twosided",
                "bsdf": {"type": "conductor", "material": "none",
                         "specular_reflectance": _rgb(r)}}
    if kind == "dielectric":
        _keys(mat, key, {"type", "ior", "transmittance"})
        ior = float(mat.get("ior", 1.5))
        if not ior > 0:
            _fail(f"{key}.ior", "expected > 0")
        t = _color(mat.get("transmittance", [1, 1, 1]), f"{key}.transmittance")
        return {"type": "dielectric", "int_ior": ior, "ext_ior": 1.0,
                "specular_transmittance": _rgb(t)}
    if kind == "conductor":
        _keys(mat, key, {"type", "alpha", "eta", "k", "reflectance"})
        alpha = float(mat.get("alpha", 0.1))
        r = _color(mat.get("reflectance", [1, 1, 1]), f"{key}.reflectance")
        if ("eta" in mat) != ("k" in mat):
            _fail(f"{key}.eta", "give both eta and k, or neither")
        if "eta" in mat:
            ior = {"eta": _rgb(_color(mat["eta"], f"{key}.eta")),
                   "k": _rgb(_color(mat["k"], f"{key}.k"))}
        else:
            ior = {"material": "none"}
        inner = {"specular_reflectance": _rgb(r), **ior}
        if alpha <= SMOOTH_ALPHA:
            inner["type"] = "conductor"
        else:
            inner.update({"type": "roughconductor", "distribution": "ggx", "alpha": alpha})
        return {"type": "twosided", "bsdf": inner}
    if kind == "rough_dielectric":
        _keys(mat, key, {"type", "ior", "alpha", "transmittance"})
        ior = float(mat.get("ior", 1.5))
        if not ior > 0:
            _fail(f"{key}.ior", "expected > 0")
        alpha = float(mat.get("alpha", 0.1))
        t = _color(mat.get("transmittance", [1, 1, 1]), f"{key}.transmittance")
        out = {"int_ior": ior, "ext_ior": 1.0, "specular_transmittance": _rgb(t)}
        if alpha <= SMOOTH_ALPHA:
            out["type"] = "dielectric"
        else:
            out.update({"type": "roughdielectric", "distribution": "ggx", "alpha": alpha})
        return out
    if kind == "plastic":
        _keys(mat, key, {"type", "albedo", "ior", "alpha"})
        albedo = mat.get("albedo", [0.5, 0.5, 0.5])
        if isinstance(albedo, dict):
            _fail(f"{key}.albedo", "textures are not converted")
        ior = float(mat.get("ior", 1.5))
        if not ior > 0:
            _fail(f"{key}.ior", "expected > 0")
        alpha = float(mat.get("alpha", 0.1))
        inner = {"int_ior": ior, "ext_ior": 1.0, "nonlinear": False,
                 "diffuse_reflectance": _rgb(_color(albedo, f"{key}.albedo"))}
        if alpha <= SMOOTH_ALPHA:
            inner["type"] = "plastic"
        else:
            inner.update({"type": "roughplastic", "distribution": "ggx", "alpha": alpha})
        return {"type": "twosided", "bsdf": inner}
    _fail(f"{key}.type", f"material type {kind!r} is not converted")


def _mitsuba():
    import mitsuba as mi
    if mi.variant() is None:
        mi.set_variant("scalar_rgb")
    return mi


def make_mesh(name, p, n, f, bsdf, emission):
    """An `mi.Mesh` from world-space arrays, with its BSDF and emitter."""
    mi = _mitsuba()
    props = mi.Properties()
    props["bsdf"] = mi.load_dict(bsdf)
    if emission is not None:
        props["emitter"] = mi.load_dict({"type": "area", "radiance": _rgb(emission)})
    used = np.unique(f)
    remap = np.full(len(p), -1, np.int64)
    remap[used] = np.arange(len(used))
    p, f = p[used], remap[f]
    if n is not None:
        n = n[used]
    mesh = mi.Mesh(name, len(p), len(f), props=props, has_vertex_normals=n is not None)
    params = mi.traverse(mesh)

    def put(key, values, dtype):
        params[key] = type(params[key])(np.ascontiguousarray(values, dtype).ravel())

    put("vertex_positions", p, np.float32)
    put("faces", f, np.uint32)
    if n is not None:
        put("vertex_normals", n, np.float32)
    params.update()
    return mesh


def read_obj(path, key, has_material):
    """Positions, vertex normals (or None) and triangle indices of an OBJ
    file, as tracer reads it with `tobj` (`triangulate`, `single_index`):
    polygons become fans around their first corner, each distinct
    (position, normal) pair one vertex, and normals are used only when
    every corner of every face names one. MTL materials are not converted,
    so a mesh that uses them must name a `material` of its own."""
    try:
        f = open(path)
    except OSError as e:
        _fail(f"{key}.file", f"cannot read {path}: {e}")
    positions, normals, corners = [], [], []
    every_corner_has_normal = True
    uses_mtl = False
    with f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            tag = parts[0]
            if tag == "v":
                positions.append([float(x) for x in parts[1:4]])
            elif tag == "vn":
                normals.append([float(x) for x in parts[1:4]])
            elif tag == "f":
                face = []
                for corner in parts[1:]:
                    fields = corner.split("/")
                    v = int(fields[0])
                    v = v - 1 if v > 0 else len(positions) + v
                    n = -1
                    if len(fields) == 3 and fields[2]:
                        n = int(fields[2])
                        n = n - 1 if n > 0 else len(normals) + n
                    else:
                        every_corner_has_normal = False
                    face.append((v, n))
                for i in range(1, len(face) - 1):
                    corners += [face[0], face[i], face[i + 1]]
            elif tag in ("mtllib", "usemtl"):
                uses_mtl = True
    if uses_mtl and not has_material:
        _fail(f"{key}.material", "a mesh with MTL materials needs a `material` of its own "
              "(MTL materials are not converted)")
    if not corners:
        _fail(f"{key}.file", f"{path} has no faces")
    pos = np.asarray(positions, float).reshape(-1, 3)
    c = np.asarray(corners, np.int64)
    if c[:, 0].min() < 0 or c[:, 0].max() >= len(pos):
        _fail(f"{key}.file", f"{path}: a face index is out of range")
    if every_corner_has_normal and normals:
        nrm = np.asarray(normals, float).reshape(-1, 3)
        if c[:, 1].min() < 0 or c[:, 1].max() >= len(nrm):
            _fail(f"{key}.file", f"{path}: a normal index is out of range")
        pairs, idx = np.unique(c, axis=0, return_inverse=True)
        return pos[pairs[:, 0]], nrm[pairs[:, 1]], idx.reshape(-1)
    return pos, None, c[:, 0]


def _object_shapes(obj, key, materials, default_bsdf, folder):
    """Mitsuba meshes for one object (one or two: with and without normals)."""
    if not isinstance(obj, dict) or "type" not in obj:
        _fail(f"{key}.type", "missing")
    kind = obj["type"]
    common = {"type", "material", "transform", "emission", "two_sided"}
    if kind == "mesh":
        _keys(obj, key, common | {"file"})
        pos_n_idx = read_obj(os.path.join(folder, str(obj["file"])), key, "material" in obj)
    elif kind == "triangles":
        _keys(obj, key, common | {"positions", "indices", "normals", "uvs"})
        pos = np.asarray(obj["positions"], float).reshape(-1, 3)
        idx = np.asarray(obj.get("indices", np.arange(len(pos))), np.int64)
        if len(idx) == 0 or len(idx) % 3 or idx.min() < 0 or idx.max() >= len(pos):
            _fail(f"{key}.indices", "expected whole triangles with indices in range")
        nrm = obj.get("normals")
        nrm = None if nrm is None else np.asarray(nrm, float).reshape(-1, 3)
        if nrm is not None and len(nrm) != len(pos):
            _fail(f"{key}.normals", "expected one normal per position")
        # uvs only matter for textures, which are refused.
        pos_n_idx = (pos, nrm, idx)
    elif kind == "quad":
        _keys(obj, key, common)
        pos_n_idx = quad()
    elif kind == "cube":
        _keys(obj, key, common)
        pos_n_idx = cube()
    elif kind == "sphere":
        _keys(obj, key, common | {"center", "radius", "subdivisions"})
        level = int(obj.get("subdivisions", 4))
        if not 0 <= level <= 10:
            _fail(f"{key}.subdivisions", "expected 0 to 10")
        pos_n_idx = sphere(_vec3(obj.get("center", [0, 0, 0]), f"{key}.center"),
                           float(obj.get("radius", 1.0)), level)
    else:
        _fail(f"{key}.type", f"object type {kind!r} is not converted")

    if "material" in obj:
        name = obj["material"]
        if name not in materials:
            _fail(f"{key}.material", f"unknown material {name!r}")
        bsdf = materials[name]
    else:
        bsdf = default_bsdf

    emission = obj.get("emission")
    if emission is not None:
        emission = _color(emission, f"{key}.emission")
        if max(emission) <= 0:
            emission = None  # black: not an emitter, as in tracer
    if emission is not None and obj.get("two_sided", False):
        _fail(f"{key}.two_sided", "two-sided emitters are not converted "
              "(Mitsuba 3's area light emits from one side)")

    m = transform_matrix(obj.get("transform"), f"{key}.transform")
    p, n, f, has_n = world_mesh(*pos_n_idx, m)
    if len(f) == 0:
        return []
    if emission is not None and has_n.any():
        _fail(key, "emitters with vertex normals are not converted (Mitsuba's "
              "area light emits on the side of the interpolated normal, tracer's "
              "on the side of the geometric normal)")
    shapes = []
    if has_n.any():
        fn = f[has_n]
        pd = p.astype(np.float64)
        ng = np.cross(pd[fn[:, 1]] - pd[fn[:, 0]], pd[fn[:, 2]] - pd[fn[:, 0]])
        # tracer turns the interpolated normal to the geometric normal's side.
        # Where the vertex normals point the other way (a mirroring transform),
        # give that triangle its own flipped copies of them.
        flip = np.einsum("ij,ij->i", n[fn].sum(axis=1), ng) < 0
        if flip.any():
            pn = p[fn].reshape(-1, 3)
            nn = (n[fn] * np.where(flip, -1.0, 1.0)[:, None, None]).reshape(-1, 3)
            shapes.append(make_mesh(f"{key}", pn, nn, np.arange(len(pn)).reshape(-1, 3),
                                    bsdf, emission))
        else:
            shapes.append(make_mesh(f"{key}", p, n, fn, bsdf, emission))
    if (~has_n).any():
        shapes.append(make_mesh(f"{key}:flat", p, None, f[~has_n], bsdf, emission))
    return shapes


def load(scene):
    """The scene as a dict: from a path (JSON only) or an already-read dict."""
    if isinstance(scene, (str, os.PathLike)):
        if str(scene).lower().endswith(".trs"):
            _fail("(file)", "T-racer .trs scenes are not converted")
        with open(scene, encoding="utf-8-sig") as f:
            scene = json.load(f)
    return scene


def settings(scene):
    """tracer's effective film and render settings (with its defaults)."""
    scene = load(scene)
    film = scene.get("film", {})
    render = scene.get("render", {})
    return {
        "width": int(film.get("width", 512)),
        "height": int(film.get("height", 512)),
        "spp": int(render.get("spp", 16)),
        "max_depth": int(render.get("max_depth", 16)),
        "seed": int(render.get("seed", 0)),
    }


SAMPLERS = ("independent", "multijitter", "ldsampler", "orthogonal", "stratified")


def _is_prime(n):
    return n >= 2 and all(n % d for d in range(2, math.isqrt(n) + 1))


def valid_spp(sampler, spp, up=False):
    """The sample count Mitsuba's `sampler` really takes nearest to `spp`: the
    largest not above it (or with `up`, the smallest not below it). Mitsuba
    itself rounds a count it cannot take up, with a warning."""
    spp = max(1, int(spp))
    if sampler == "ldsampler":  # a square power of two: 1, 4, 16, 64, 256 ...
        r = 1
        while (2 * r) ** 2 <= spp:
            r *= 2
        return 4 * r * r if up and r * r < spp else r * r
    if sampler == "orthogonal":  # the square of a prime, at least 4
        if up:
            r = max(2, math.isqrt(spp - 1) + 1)
            while not _is_prime(r):
                r += 1
            return r * r
        r = max(2, math.isqrt(spp))
        while r > 2 and not _is_prime(r):
            r -= 1
        return r * r
    if sampler == "stratified":  # a square
        r = math.isqrt(spp)
        return (r + 1) ** 2 if up and r * r < spp else max(1, r * r)
    if sampler == "multijitter":  # a near-square grid, as Mitsuba rounds it
        r = max(1, math.isqrt(spp))
        return r * ((spp + r - 1) // r)
    return spp


def convert(scene, *, integrator="path", sampler="independent", spp=None,
            max_depth=None, width=None, height=None, seed=None,
            samples_per_pass=None):
    """A dict for `mi.load_dict`: the scene, its camera, film and sampler, and
    the integrator (`path` or `ptracer`). Unset arguments take the scene's
    values (tracer's defaults where the scene gives none)."""
    folder = (os.path.dirname(os.path.abspath(scene))
              if isinstance(scene, (str, os.PathLike)) else os.getcwd())
    scene = load(scene)
    _keys(scene, "", {"format", "name", "camera", "film", "render", "materials",
                      "objects", "lights"})
    if scene.get("format", 1) not in FORMAT_VERSIONS:
        _fail("format", f"format version {scene['format']} is not converted (only 1 and 2)")
    s = settings(scene)

    cam = scene["camera"]
    _keys(cam, "camera", {"type", "position", "look_at", "up", "fov", "aperture_radius",
                          "focus_distance"})
    if cam.get("type", "perspective") != "perspective":
        _fail("camera.type", "only perspective cameras")
    film = scene.get("film", {})
    _keys(film, "film", {"width", "height", "output", "tonemap", "exposure"})
    render = scene.get("render", {})
    _keys(render, "render", {"integrator", "spp", "time_limit", "max_depth", "seed"})

    mi = _mitsuba()
    to_world = mi.ScalarTransform4f().look_at(
        origin=[float(x) for x in _vec3(cam["position"], "camera.position")],
        target=[float(x) for x in _vec3(cam["look_at"], "camera.look_at")],
        up=[float(x) for x in _vec3(cam.get("up", [0, 1, 0]), "camera.up")])
    spp = s["spp"] if spp is None else int(spp)
    if sampler not in SAMPLERS:
        _fail("sampler", f"unknown Mitsuba sampler {sampler!r}")
    position = _vec3(cam["position"], "camera.position")
    target = _vec3(cam["look_at"], "camera.look_at")
    aperture = float(cam.get("aperture_radius", 0.0))
    lens = {}
    if aperture > 0:
        focus = cam.get("focus_distance")
        if focus is None:
            focus = math.dist(position, target)
        lens = {"type": "thinlens", "aperture_radius": aperture,
                "focus_distance": float(focus)}
    out = {
        "type": "scene",
        "sensor": {
            "type": "perspective",
            "fov_axis": "y",
            "fov": float(cam.get("fov", 40.0)),
            "to_world": to_world,
            "near_clip": 1e-4,
            "far_clip": 1e8,
            "film": {
                "type": "hdrfilm",
                "width": s["width"] if width is None else int(width),
                "height": s["height"] if height is None else int(height),
                "pixel_format": "rgb",
                "rfilter": {"type": "box"},
            },
            **lens,
            "sampler": {
                "type": sampler,
                "sample_count": valid_spp(sampler, spp),
                "seed": s["seed"] if seed is None else int(seed),
            },
        },
    }
    depth = s["max_depth"] if max_depth is None else int(max_depth)
    if integrator not in ("path", "ptracer"):
        _fail("integrator", f"unknown Mitsuba integrator {integrator!r}")
    out["integrator"] = {"type": integrator, "max_depth": depth, "hide_emitters": False}
    if samples_per_pass:
        out["integrator"]["samples_per_pass"] = int(samples_per_pass)

    materials = {}
    mats = scene.get("materials", {})
    if not isinstance(mats, dict):
        _fail("materials", "expected an object")
    for name, mat in mats.items():
        materials[name] = bsdf_dict(mat, f"materials.{name}")
    default_bsdf = materials.get("default") or bsdf_dict(
        {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}, "(built-in default)")

    count = 0
    for i, obj in enumerate(scene.get("objects", [])):
        for shape in _object_shapes(obj, f"objects[{i}]", materials, default_bsdf, folder):
            out[f"shape_{count:04d}"] = shape
            count += 1

    for i, light in enumerate(scene.get("lights", [])):
        key = f"lights[{i}]"
        kind = light.get("type") if isinstance(light, dict) else None
        if kind == "point":
            _keys(light, key, {"type", "position", "intensity"})
            out[f"light_{i:03d}"] = {
                "type": "point",
                "position": [float(x) for x in _vec3(light["position"], f"{key}.position")],
                "intensity": _rgb(_color(light["intensity"], f"{key}.intensity"))}
        elif kind == "directional":
            _keys(light, key, {"type", "direction", "irradiance"})
            d = _vec3(light["direction"], f"{key}.direction")
            if not np.any(d):
                _fail(f"{key}.direction", "zero")
            out[f"light_{i:03d}"] = {
                "type": "directional",
                "direction": [float(x) for x in d / np.linalg.norm(d)],
                "irradiance": _rgb(_color(light["irradiance"], f"{key}.irradiance"))}
        elif kind == "environment":
            _keys(light, key, {"type", "radiance", "file", "scale", "transform"})
            scale = float(light.get("scale", 1.0))
            if ("radiance" in light) == ("file" in light):
                _fail(key, "give exactly one of radiance and file")
            if "radiance" in light:
                radiance = [x * scale for x in _color(light["radiance"], f"{key}.radiance")]
                out[f"light_{i:03d}"] = {"type": "constant", "radiance": _rgb(radiance)}
            else:
                m = transform_matrix(light.get("transform"), f"{key}.transform")
                out[f"light_{i:03d}"] = {
                    "type": "envmap",
                    "filename": os.path.join(folder, light["file"]),
                    "scale": scale,
                    "to_world": mi.ScalarTransform4f(m.tolist())}
        else:
            _fail(f"{key}.type", f"light type {kind!r} is not converted "
                  "(point, directional and environment are; spot falloffs differ)")
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--integrator", default="path", choices=["path", "ptracer"])
    ap.add_argument("--sampler", default="independent", choices=SAMPLERS)
    ap.add_argument("--spp", type=int)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int)
    ap.add_argument("-o", "--output", help="render with Mitsuba and write this EXR")
    a = ap.parse_args(argv)
    import mitsuba as mi
    import drjit as dr
    mi.set_variant(a.variant)
    if a.threads:
        dr.set_thread_count(a.threads)
    try:
        d = convert(a.scene, integrator=a.integrator, sampler=a.sampler, spp=a.spp, seed=a.seed)
    except Unsupported as e:
        print(f"error: {a.scene}: {e}", file=sys.stderr)
        return 2
    shapes = [k for k in d if k.startswith("shape_")]
    tris = sum(int(np.asarray(d[k].face_count()).ravel()[0]) for k in shapes)
    print(f"{a.scene}: {len(shapes)} meshes, {tris} triangles, "
          f"{sum(1 for k in d if k.startswith('light_'))} lights, "
          f"{d['sensor']['film']['width']}x{d['sensor']['film']['height']}, "
          f"{d['integrator']['type']} max_depth {d['integrator']['max_depth']}, "
          f"{d['sensor']['sampler']['type']} {d['sensor']['sampler']['sample_count']} spp")
    if a.output:
        img = mi.render(mi.load_dict(d), seed=a.seed)
        mi.Bitmap(img).write(a.output)
        print(f"wrote {a.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
