"""Evaluated Blender meshes as binary PLY files bounce reads (through Assimp): one file per
material slot that has triangles, corners with their split normals and the active uv map, in
the object's own space (its placement is the scene file's transform)."""

import numpy as np


def mesh_arrays(mesh):
    """{slot index: (positions, normals, uvs or None)}, each (3 x triangles, k) float32."""
    mesh.calc_loop_triangles()
    if hasattr(mesh, "calc_normals_split"):
        mesh.calc_normals_split()
    tris = len(mesh.loop_triangles)
    if tris == 0:
        return {}
    loops = np.empty(tris * 3, np.int32)
    mesh.loop_triangles.foreach_get("loops", loops)
    slots = np.empty(tris, np.int32)
    mesh.loop_triangles.foreach_get("material_index", slots)
    vertex_of = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", vertex_of)
    co = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", co)
    normals = np.empty(len(mesh.loops) * 3, np.float32)
    mesh.loops.foreach_get("normal", normals)
    uv = None
    if mesh.uv_layers.active is not None:
        uv = np.empty(len(mesh.loops) * 2, np.float32)
        mesh.uv_layers.active.data.foreach_get("uv", uv)
        uv = uv.reshape(-1, 2)[loops]
    positions = co.reshape(-1, 3)[vertex_of[loops]]
    normals = normals.reshape(-1, 3)[loops]
    out = {}
    corner_slots = np.repeat(slots, 3)
    for slot in np.unique(slots):
        keep = corner_slots == slot
        out[int(slot)] = (positions[keep], normals[keep], None if uv is None else uv[keep])
    return out


def write_ply(path, positions, normals, uvs):
    """A binary PLY of unindexed triangles (Assimp joins identical corners as it reads)."""
    n = len(positions)
    fields = [("p", "<f4", 3), ("n", "<f4", 3)]
    props = ["x", "y", "z", "nx", "ny", "nz"]
    if uvs is not None:
        fields.append(("uv", "<f4", 2))
        props += ["s", "t"]
    vertices = np.empty(n, dtype=fields)
    vertices["p"] = positions
    vertices["n"] = normals
    if uvs is not None:
        vertices["uv"] = uvs
    faces = np.empty(n // 3, dtype=[("count", "u1"), ("index", "<i4", 3)])
    faces["count"] = 3
    faces["index"] = np.arange(n, dtype=np.int32).reshape(-1, 3)
    header = ["ply", "format binary_little_endian 1.0", f"element vertex {n}"]
    header += [f"property float {p}" for p in props]
    header += [f"element face {n // 3}", "property list uchar int vertex_indices", "end_header", ""]
    with open(path, "wb") as f:
        f.write("\n".join(header).encode("ascii"))
        vertices.tofile(f)
        faces.tofile(f)
