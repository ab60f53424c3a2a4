#!/usr/bin/env python3
"""Writes the malformed input files of tests/data/bad/ (the expected error of each is in
EXPECTED.tsv, checked by tests/io/bad_input_test.cpp). Deterministic; run from anywhere."""
import lzma
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
TRI = "v 0 0 0\nv 1 0 0\nv 0 1 0\n"


def write(name, data):
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode("latin-1"))


def ply_binary(vertices, faces, order="<", coord="f", declared_vertices=None, extra_header=""):
    fmt = "binary_little_endian" if order == "<" else "binary_big_endian"
    coord_name = {"f": "float", "d": "double"}[coord]
    header = ("ply\nformat %s 1.0\n%selement vertex %d\nproperty %s x\nproperty %s y\n"
              "property %s z\nelement face %d\nproperty list uchar int vertex_indices\n"
              "end_header\n" % (fmt, extra_header,
                                len(vertices) if declared_vertices is None else declared_vertices,
                                coord_name, coord_name, coord_name, len(faces))).encode()
    body = b"".join(struct.pack(order + coord * 3, *v) for v in vertices)
    body += b"".join(struct.pack(order + "B", len(f)) + struct.pack(order + "i" * len(f), *f)
                     for f in faces)
    return header + body


def stl_binary(triangles, declared=None):
    data = b"bad".ljust(80, b" ") + struct.pack("<I", len(triangles) if declared is None
                                                else declared)
    for t in triangles:
        data += struct.pack("<3f", 0, 0, 1) + b"".join(struct.pack("<3f", *p) for p in t)
        data += b"\0\0"
    return data


SQUARE = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]


def main():
    # Empty and not-a-mesh files.
    write("empty.obj", "")
    write("empty.ply", "")
    write("empty.off", "")
    write("empty.stl", "")
    write("whitespace_only.obj", "\n  \n\t\n")
    write("comments_only.off", "# nothing\n# here\n")
    write("unknown_extension.3ds", TRI + "f 1 2 3\n")
    write("no_faces.obj", TRI)
    # OBJ.
    write("obj_index_out_of_range.obj", TRI + "f 1 2 3\nf 1 2 4\n")
    write("obj_index_zero.obj", TRI + "f 0 1 2\n")
    write("obj_relative_index_before_first.obj", TRI + "f -1 -2 -4\n")
    write("obj_nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n")
    write("obj_inf.obj", "v 0 0 0\nv 1 0 0\nv 0 -inf 0\nf 1 2 3\n")
    write("obj_overflow.obj", "v 0 0 0\nv 1e400 0 0\nv 0 1 0\nf 1 2 3\n")
    write("obj_two_vertex_face.obj", TRI + "f 1 2\n")
    write("obj_repeated_index.obj", TRI + "f 1 2 2\n")
    write("obj_missing_coordinate.obj", "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n")
    write("obj_garbage_coordinate.obj", "v 0 0 0\nv 1 0x1g 0\nv 0 1 0\nf 1 2 3\n")
    write("obj_non_utf8.obj", "v 0 0 0\nv 1 \xe9\xe8 0\nv 0 1 0\nf 1 2 3\n")
    write("obj_huge_index.obj", TRI + "f 1 2 99999999999999999999\n")
    # Mixed line endings: \n, \r\n and a lone \r; the bad index is on line 6 as an editor shows.
    write("obj_mixed_line_endings.obj", "v 0 0 0\r\nv 1 0 0\nv 0 1 0\rv 1 1 0\r\nf 1 2 3\nf 2 4 5\n")
    # OFF.
    write("off_wrong_counts.off", "OFF\n10 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    write("off_huge_counts.off", "OFF\n2000000000 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    write("off_negative_index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n")
    write("off_negative_count.off", "OFF\n-3 1 0\n")
    write("off_polygon_two_vertices.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n")
    write("off_not_off.off", "PLY\n3 1 0\n")
    write("off_binary.off", "OFF BINARY\n" + "\0" * 16)
    write("off_four_d.off", "4OFF\n3 1 0\n0 0 0 1\n1 0 0 1\n0 1 0 1\n3 0 1 2\n")
    # PLY.
    good = ply_binary(SQUARE, [(0, 1, 2), (0, 2, 3)])
    write("ply_truncated_binary.ply", good[:-7])
    write("ply_truncated_in_vertices.ply", good[:good.index(b"end_header\n") + 11 + 20])
    write("ply_huge_count.ply", ply_binary(SQUARE, [(0, 1, 2)], declared_vertices=4000000000))
    write("ply_index_out_of_range.ply", ply_binary(SQUARE, [(0, 1, 2), (0, 2, 4)]))
    write("ply_negative_index_big_endian.ply", ply_binary(SQUARE, [(0, 1, -3)], order=">"))
    write("ply_nan_binary.ply", ply_binary(SQUARE[:2] + [(float("nan"), 1, 0)], [(0, 1, 2)],
                                           coord="d"))
    write("ply_polygon_two_vertices.ply", ply_binary(SQUARE, [(0, 1, 2), (0, 1)]))
    write("ply_no_end_header.ply", "ply\nformat ascii 1.0\nelement vertex 3\n")
    write("ply_unknown_format.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n")
    write("ply_float_indices.ply",
          "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
          "property float z\nelement face 1\nproperty list uchar float vertex_indices\n"
          "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    # Found by fuzzing (a heap overflow before the fix): a second 'face' element.
    write("ply_two_face_elements.ply",
          "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
          "property float z\nelement face 1\nproperty uchar flags\n"
          "property list uchar int vertex_indices\nelement face 1\nproperty uchar flags\n"
          "end_header\n0 0 0\n1 0 0\n0 1 0\n0 3 0 1 2\n0\n")
    write("ply_missing_z.ply",
          "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
          "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0\n1 0\n0 1\n"
          "3 0 1 2\n")
    write("ply_ascii_inf.ply",
          "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
          "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
          "end_header\n0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n")
    write("ply_ascii_bad_index.ply",
          "ply\r\nformat ascii 1.0\r\nelement vertex 3\r\nproperty float x\r\nproperty float y\r\n"
          "property float z\r\nelement face 1\r\nproperty list uchar int vertex_indices\r\n"
          "end_header\r\n0 0 0\r\n1 0 0\r\n0 1 0\r\n3 0 1 two\r\n")
    write("ply_ascii_negative_list_length.ply",
          "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
          "property float z\nelement face 1\nproperty list char int vertex_indices\n"
          "end_header\n0 0 0\n1 0 0\n0 1 0\n-3 0 1 2\n")
    # STL.
    tri = [((0, 0, 0), (1, 0, 0), (0, 1, 0)), ((1, 0, 0), (1, 1, 0), (0, 1, 0))]
    write("stl_truncated_binary.stl", stl_binary(tri)[:-10])
    write("stl_wrong_count_binary.stl", stl_binary(tri, declared=7))
    write("stl_nan_binary.stl", stl_binary([((0, 0, 0), (1, float("nan"), 0), (0, 1, 0))]))
    write("stl_ascii_truncated.stl", "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"
                                     "vertex 1 0 0\n")
    write("stl_ascii_garbage.stl", "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"
                                   "vertex 1 zero 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid\n")
    # xz.
    compressed = lzma.compress((TRI + "f 1 2 3\n").encode())
    write("truncated.obj.xz", compressed[:len(compressed) // 2])
    write("not_xz.obj.xz", TRI + "f 1 2 3\n")
    corrupt = bytearray(compressed)
    corrupt[len(corrupt) // 2] ^= 0x55
    write("corrupt.obj.xz", bytes(corrupt))
    write("nan_inside.obj.xz", lzma.compress("v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n".encode()))
    # Scenarios (TOML): errors give file:line:column and the key.
    write("scenario_unknown_key.toml",
          'mesh = { builtin = "cylinder", vertices = 100 }\n[[handle]]\n'
          'select.slab = { axis = "z", from = 0.0, to = 0.1 }\nrotation = 3\n')
    write("scenario_syntax_error.toml", 'mesh = "a.obj"\n[[handle]\nname = "x"\n')
    write("scenario_non_utf8.toml", 'mesh = "caf\xe9.obj"\n')
    write("scenario_index_out_of_range.toml",
          'mesh = { builtin = "cylinder", vertices = 100 }\n[[handle]]\nname = "pin"\n'
          'select.indices = [0, 1,\n  100000]\n')
    write("scenario_missing_mesh.toml", 'mesh = "does-not-exist.obj"\n')
    write("scenario_bad_mesh.toml", '# the mesh file is broken\nmesh = "obj_nan.obj"\n')
    write("scenario_nan_translate.toml",
          'mesh = { builtin = "cylinder", vertices = 100 }\n[[handle]]\n'
          'select.slab = { axis = "z", from = 0.0, to = 0.1 }\ntranslate = [0.0, nan, 0.0]\n')
    write("scenario_empty_selection.toml",
          'mesh = { builtin = "cylinder", vertices = 100 }\n[[handle]]\nname = "air"\n'
          'select.ball = { center = [5.0, 5.0, 5.0], radius = 0.01 }\n')
    write("scenario_huge_refine.toml", 'mesh = { builtin = "cylinder", vertices = 100000 }\n'
                                       'refine = 8\n')


if __name__ == "__main__":
    main()
