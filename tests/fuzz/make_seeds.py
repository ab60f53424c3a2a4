#!/usr/bin/env python3
"""Writes the fuzz seed corpus (tests/fuzz/corpus/<target>/) and the files the scenario seeds
name (tests/fuzz/scenario_files/). Small valid inputs that reach every branch of each reader;
libFuzzer mutates them. Run from anywhere; rewrites the files in place (deterministic)."""
import lzma
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))

# An octahedron: 6 vertices, 8 faces, closed and consistently oriented.
V = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
F = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]


def write(path, data):
    path = os.path.join(HERE, path)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def obj_text(newline="\n"):
    lines = ["# octahedron", "o octahedron"]
    lines += ["v %g %g %g" % v for v in V]
    lines += ["f %d %d %d" % tuple(i + 1 for i in f) for f in F]
    return newline.join(lines) + newline


def ply_header(fmt, vertex_props, face_list, extra=""):
    return ("ply\nformat %s 1.0\ncomment fuzz seed\n%selement vertex %d\n%selement face %d\n"
            "property list %s vertex_indices\nend_header\n" %
            (fmt, extra, len(V), "".join("property %s %s\n" % p for p in vertex_props), len(F),
             face_list)).encode()


def binary_ply(order, coord, count_type, index_type, with_normals=False):
    props = [(coord, "x"), (coord, "y"), (coord, "z")]
    if with_normals:
        props += [("float", "nx"), ("float", "ny"), ("float", "nz"), ("uchar", "red")]
    fmt = "binary_little_endian" if order == "<" else "binary_big_endian"
    extra = "element material 1\nproperty uchar id\n"
    data = ply_header(fmt, props, "%s %s" % (count_type, index_type), extra)
    data += struct.pack(order + "B", 7)  # the material element comes first
    codes = {"float": "f", "double": "d", "uchar": "B", "int": "i", "uint": "I", "short": "h",
             "ushort": "H", "char": "b"}
    for v in V:
        data += struct.pack(order + codes[coord] * 3, *v)
        if with_normals:
            data += struct.pack(order + "fffB", *v, 200)
    for f in F:
        data += struct.pack(order + codes[count_type], 3)
        data += struct.pack(order + codes[index_type] * 3, *f)
    return data


def stl_ascii():
    out = ["solid octahedron"]
    for f in F:
        out += ["  facet normal 0 0 0", "    outer loop"]
        out += ["      vertex %g %g %g" % V[i] for i in f]
        out += ["    endloop", "  endfacet"]
    return "\n".join(out + ["endsolid octahedron"]) + "\n"


def stl_binary():
    data = b"binary octahedron".ljust(80, b" ") + struct.pack("<I", len(F))
    for f in F:
        data += struct.pack("<3f", 0, 0, 0)
        for i in f:
            data += struct.pack("<3f", *V[i])
        data += struct.pack("<H", 0)
    return data


def main():
    write("corpus/obj/octahedron.obj", obj_text())
    write("corpus/obj/crlf.obj", obj_text("\r\n"))
    write("corpus/obj/polygons.obj",
          "mtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 1 1.0\nvt 0 0\n"
          "vn 0 0 1\ng quad\ns off\nusemtl m\nf 1/1/1 2/1/1 3/1/1 4/1/1\nf -5//1 -4//1 -1//1\n"
          "f 2/1 3/1 5/1\nf 3 4 5\nf 4 1 5\nl 1 2\np 3\n")
    write("corpus/ply_ascii/octahedron.ply",
          ply_header("ascii", [("float", "x"), ("float", "y"), ("float", "z")], "uchar int") +
          "".join("%g %g %g\n" % v for v in V).encode() +
          "".join("3 %d %d %d\n" % f for f in F).encode())
    write("corpus/ply_ascii/extras.ply",
          "ply\nformat ascii 1.0\nobj_info generated\nelement vertex 5\nproperty double x\n"
          "property double y\nproperty double z\nproperty uchar red\n"
          "property list uchar float texcoord\nelement face 2\nproperty uchar flags\n"
          "property list uint int vertex_index\nelement edge 1\nproperty int vertex1\n"
          "property int vertex2\nend_header\n0 0 0 255 2 0.5 0.5\n1 0 0 0 0\n1 1 0 0 0\n"
          "0 1 0 0 0\n0.5 0.5 1e-3 9 1 0\n0 4 0 1 2 3\n1 3 0 1 4\n0 1\n")
    write("corpus/ply_binary/le_float_int.ply", binary_ply("<", "float", "uchar", "int"))
    write("corpus/ply_binary/be_double_uint.ply", binary_ply(">", "double", "ushort", "uint"))
    write("corpus/ply_binary/le_normals_short.ply",
          binary_ply("<", "float", "char", "short", with_normals=True))
    write("corpus/off/octahedron.off",
          "OFF\n%d %d 0\n" % (len(V), len(F)) + "".join("%g %g %g\n" % v for v in V) +
          "".join("3 %d %d %d\n" % f for f in F))
    write("corpus/off/coff_polygons.off",
          "COFF\n# comment\n\n5 2 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n1 1 0 0 0 255 255\n"
          "0 1 0 1 1 1 255\n0.5 0.5 1e-3 0 0 0 0\n4 0 1 2 3  # quad\n3 0 1 4\n")
    write("corpus/off/noff_inline_counts.off",
          "NOFF 4 2 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n1 1 0 0 0 1\n3 0 1 2\n3 1 3 2\n")
    write("corpus/stl/octahedron_ascii.stl", stl_ascii())
    write("corpus/stl/octahedron_binary.stl", stl_binary())
    write("corpus/xz/octahedron.obj.xz", lzma.compress(obj_text().encode(), preset=1))
    # Two concatenated streams, as `xz` itself accepts.
    half = obj_text().encode()
    write("corpus/xz/two_streams.obj.xz",
          lzma.compress(half[:60], preset=0) +
          lzma.compress(half[60:], preset=0, check=lzma.CHECK_NONE))

    write("scenario_files/octahedron.obj", obj_text())
    write("scenario_files/octahedron_moved.obj", obj_text().replace("v 1 0 0", "v 2 0 0"))
    write("scenario_files/handles.txt", "0 1\n2\n")
    write("corpus/scenario/builtin_cylinder.toml",
          'mesh = { builtin = "cylinder", vertices = 200 }\n\n[[handle]]\nname = "bottom"\n'
          'select.slab = { axis = "z", from = 0.0, to = 0.1 }\n\n[[handle]]\nname = "top"\n'
          'select.slab = { axis = "z", from = 0.9, to = 1.0 }\n'
          'rotate = { axis = [1.0, 0.0, 0.0], degrees = 45.0, center = [0.5, 0.5, 1.0] }\n'
          'translate = [0.0, 0.1, 0.0]\n')
    write("corpus/scenario/builtin_plane_ball.toml",
          'mesh = { builtin = "plane", vertices = 100 }\nrefine = 1\n[[handle]]\n'
          'select.ball = { center = [0.5, 0.5, 0.0], radius = 0.2 }\ntranslate = [0, 0, 0.3]\n')
    write("corpus/scenario/file_indices.toml",
          'mesh = "octahedron.obj"\ninitial = "octahedron_moved.obj"\n[[handle]]\n'
          'select.indices = [0, 3]\ntarget = "initial"\n[[handle]]\nname = "file"\n'
          'select.index_file = "handles.txt"\nrotate = { axis = [0, 1, 0], degrees = -30 }\n')


if __name__ == "__main__":
    main()
