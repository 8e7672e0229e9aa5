#!/usr/bin/env python3
"""Writes lodkit's malformed-input corpus into tests/malformed/.

Every file is a small, deliberately broken PLY, OBJ, STL, glTF/GLB, XYZ,
PTS, LAS/LAZ or .conf file whose name says what is wrong with it. `lodkit_mesh::io::load` must
return an error for each one, without panicking and without allocating from
an unchecked count; crates/mesh/tests/malformed.rs checks exactly that.

Standard library only; the output is byte-for-byte deterministic, so running
it again on an unchanged script changes nothing in git.

Usage: python3 scripts/make_malformed_corpus.py [OUTPUT_DIR]
"""

import base64
import json
import os
import shutil
import struct
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "tests", "malformed")

FILES = {}


def add(name, data):
    if isinstance(data, str):
        data = data.encode()
    assert name not in FILES, name
    FILES[name] = data


# ------------------------------------------------------------------ PLY

def ply_header(fmt, vertices, faces, vprops=("float x", "float y", "float z"),
               face_prop="property list uchar int vertex_indices"):
    lines = ["ply", f"format {fmt} 1.0", f"element vertex {vertices}"]
    lines += [f"property {p}" for p in vprops]
    if faces is not None:
        lines += [f"element face {faces}", face_prop]
    lines.append("end_header")
    return "\n".join(lines) + "\n"


TRI_ASCII_BODY = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"


def ply_bin_tri(faces=((0, 1, 2),), verts=((0, 0, 0), (1, 0, 0), (0, 1, 0))):
    b = b"".join(struct.pack("<3f", *v) for v in verts)
    for f in faces:
        b += struct.pack("<B", len(f)) + struct.pack(f"<{len(f)}i", *f)
    return b


add("ply_wrong_magic.ply", "plx\n" + ply_header("ascii", 3, 1)[4:] + TRI_ASCII_BODY)
add("ply_missing_end_header.ply",
    ply_header("ascii", 3, 1).replace("end_header\n", "") + TRI_ASCII_BODY)
add("ply_bad_format_line.ply", ply_header("ebcdic", 3, 1) + TRI_ASCII_BODY)
add("ply_vertex_count_huge.ply",
    ply_header("binary_little_endian", 4000000000, 1).encode() + ply_bin_tri())
add("ply_face_count_huge.ply",
    ply_header("binary_little_endian", 3, 4000000000).encode() + ply_bin_tri())
add("ply_truncated_body.ply",
    ply_header("binary_little_endian", 3, 1).encode() + ply_bin_tri()[:30])
add("ply_header_only.ply", ply_header("binary_little_endian", 3, 1))
add("ply_index_out_of_range.ply", ply_header("ascii", 3, 1) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n")
add("ply_index_out_of_range_binary.ply",
    ply_header("binary_little_endian", 3, 1).encode() + ply_bin_tri(faces=((0, 1, 3),)))
add("ply_negative_index.ply", ply_header("ascii", 3, 1) + "0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n")
add("ply_nan_coordinate.ply", ply_header("ascii", 3, 1) + "0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n")
add("ply_inf_coordinate.ply",
    ply_header("binary_little_endian", 3, 1).encode()
    + ply_bin_tri(verts=((0, 0, 0), (float("inf"), 0, 0), (0, 1, 0))))
add("ply_list_count_overrun.ply",
    ply_header("binary_little_endian", 3, 1).encode()
    + ply_bin_tri()[:36] + struct.pack("<B3i", 255, 0, 1, 2))
add("ply_unknown_property_type.ply",
    ply_header("ascii", 3, 1, vprops=("float x", "float y", "quaternion z")) + TRI_ASCII_BODY)
add("ply_negative_count.ply", ply_header("ascii", -3, 1) + TRI_ASCII_BODY)
add("ply_repeated_face_index.ply", ply_header("ascii", 3, 1) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 1\n")
add("ply_face_float_indices.ply",
    ply_header("ascii", 3, 1, face_prop="property list uchar float vertex_indices")
    + "0 0 0\n1 0 0\n0 1 0\n3 0.5 1.5 2\n")
add("ply_ascii_not_a_number.ply", ply_header("ascii", 3, 1) + "0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n")
add("ply_empty.ply", b"")
# Binary bodies must end with the last declared element, and faces are
# checked alike by the in-core and the streaming (out-of-core) reader.
add("ply_trailing_bytes_binary.ply",
    ply_header("binary_little_endian", 3, 1).encode() + ply_bin_tri() + b"garbage")
add("ply_face_count_below_data_binary.ply",
    ply_header("binary_little_endian", 3, 1).encode() + ply_bin_tri(faces=((0, 1, 2), (2, 1, 0))))
add("ply_repeated_face_index_binary.ply",
    ply_header("binary_little_endian", 3, 1).encode() + ply_bin_tri(faces=((2, 2, 2),)))
add("ply_vertex_count_one_high_binary.ply",
    ply_header("binary_little_endian", 4, 2).encode()
    + ply_bin_tri(faces=((0, 1, 2), (2, 1, 0), (0, 2, 1))))

# ------------------------------------------------------------------ OBJ

TRI_V = "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
add("obj_empty.obj", b"")
add("obj_no_faces.obj", TRI_V)
add("obj_index_out_of_range.obj", TRI_V + "f 1 2 4\n")
add("obj_index_zero.obj", TRI_V + "f 0 1 2\n")
add("obj_negative_index_before_start.obj", TRI_V + "f -1 -2 -4\n")
# tobj 4.0 computes vt * 2 + 1 unchecked: this index overflows it.
add("obj_texcoord_index_overflow.obj", TRI_V + "vt 0 0\nf 1/1 2/-9223372036854775807 3/1\n")
add("obj_nan_coordinate.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n")
add("obj_inf_coordinate.obj", "v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n")
add("obj_garbage_tokens.obj", TRI_V + "v 1 @ 1\nf 1 2 3\n")
add("obj_face_one_vertex.obj", TRI_V + "f 1\n")
add("obj_face_two_vertices.obj", TRI_V + "f 1 2\n")
add("obj_face_repeated_index.obj", TRI_V + "f 1 2 2\n")
add("obj_mixed_vertex_colors.obj", TRI_V + "v 1 1 1 0.5 0.5 0.5\nf 1 2 4\n")
add("obj_invalid_utf8.obj", TRI_V.encode() + b"f 1 2 3\n\xff\xfe\n")

# ------------------------------------------------------------------ STL

def stl_bin(count, facets):
    header = b"malformed corpus".ljust(80, b"\0")
    body = b"".join(struct.pack("<12fH", *f, 0) for f in facets)
    return header + struct.pack("<I", count) + body


FACET = (0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0)
ASCII_TRI = ("solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n"
             "   vertex 1 0 0\n   vertex 0 1 0\n  endloop\n endfacet\n")
add("stl_empty.stl", b"")
add("stl_header_only_80_bytes.stl", b"binary header".ljust(80, b"\0"))
add("stl_binary_count_mismatch.stl", stl_bin(3, [FACET, FACET]))
add("stl_binary_count_huge.stl", stl_bin(4000000000, [FACET]))
add("stl_binary_truncated.stl", stl_bin(2, [FACET, FACET])[:-20])
add("stl_binary_nan.stl", stl_bin(1, [(0, 0, 1, float("nan"), 0, 0, 1, 0, 0, 0, 1, 0)]))
add("stl_binary_zero_triangles.stl", stl_bin(0, []))
add("stl_ascii_unterminated.stl", ASCII_TRI)
add("stl_ascii_missing_endloop.stl", ASCII_TRI.replace("  endloop\n", "") + "endsolid t\n")
add("stl_ascii_not_a_number.stl", ASCII_TRI.replace("vertex 1 0 0", "vertex 1 O 0") + "endsolid t\n")
add("stl_ascii_facet_four_vertices.stl",
    ASCII_TRI.replace("   vertex 0 1 0\n", "   vertex 0 1 0\n   vertex 1 1 0\n") + "endsolid t\n")
add("stl_ascii_nan.stl", ASCII_TRI.replace("vertex 0 0 0", "vertex nan 0 0") + "endsolid t\n")

# ------------------------------------------------------------------ glTF / GLB

QUAD = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<3H", 0, 1, 2) + b"\0\0"


def gltf_doc(bin_bytes=QUAD, uri=None, pos_accessor=0, index_count=3, pos_count=3,
             extra_index=None, index_view_len=6, sparse=False, nodes=None):
    if uri is None:
        uri = "data:application/octet-stream;base64," + base64.b64encode(bin_bytes).decode()
    buf = {"byteLength": len(bin_bytes)}
    if uri is not False:
        buf["uri"] = uri
    idx_acc = {"bufferView": 1, "componentType": 5123, "count": index_count, "type": "SCALAR"}
    if sparse:
        idx_acc["sparse"] = {"count": 1, "indices": {"bufferView": 1, "componentType": 5123},
                             "values": {"bufferView": 1}}
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [buf],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                        {"buffer": 0, "byteOffset": 36, "byteLength": index_view_len}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": pos_count,
                       "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}, idx_acc],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos_accessor}, "indices": 1}]}],
        "nodes": nodes if nodes is not None else [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    }
    return json.dumps(doc, sort_keys=True)


def glb(json_text, bin_bytes=QUAD, json_len=None, bin_len=None, total=None):
    js = json_text.encode()
    js += b" " * (-len(js) % 4)
    out = struct.pack("<I4s", len(js) if json_len is None else json_len, b"JSON") + js
    if bin_bytes is not None:
        b = bin_bytes + b"\0" * (-len(bin_bytes) % 4)
        out += struct.pack("<I4s", len(b) if bin_len is None else bin_len, b"BIN\0") + b
    length = 12 + len(out) if total is None else total
    return struct.pack("<4sII", b"glTF", 2, length) + out


GLB_JSON = gltf_doc(uri=False)
add("glb_bad_magic.glb", b"gLTF" + glb(GLB_JSON)[4:])
add("glb_truncated_header.glb", glb(GLB_JSON)[:10])
add("glb_header_length_under_12.glb", glb(GLB_JSON, total=4))
add("glb_header_length_beyond_file.glb", glb(GLB_JSON, total=100000))
add("glb_chunk_length_beyond_file.glb", glb(GLB_JSON, bin_len=4000000000))
add("glb_json_chunk_length_beyond_file.glb", glb(GLB_JSON, json_len=4000000000))
add("glb_missing_bin_chunk.glb", glb(GLB_JSON, bin_bytes=None))
add("glb_version_1.glb", b"glTF" + struct.pack("<I", 1) + glb(GLB_JSON)[8:])
add("gltf_json_garbage.gltf", '{"asset": {"version": "2.0"}, "meshes": [ {,,, ]')
add("gltf_not_json.gltf", "this is not a glTF file\n")
add("gltf_empty.gltf", b"")
add("gltf_accessor_out_of_buffer_range.gltf", gltf_doc(pos_count=1000))
add("gltf_view_beyond_buffer.gltf", gltf_doc(index_view_len=4000, index_count=3))
add("gltf_index_out_of_range.gltf",
    gltf_doc(bin_bytes=struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<3H", 0, 1, 9) + b"\0\0"))
add("gltf_missing_buffer_file.gltf", gltf_doc(uri="no_such_buffer.bin"))
add("gltf_http_buffer.gltf", gltf_doc(uri="http://example.invalid/buffer.bin"))
add("gltf_data_uri_not_base64.gltf", gltf_doc(uri="data:application/octet-stream,AAAA"))
add("gltf_data_uri_bad_base64.gltf", gltf_doc(uri="data:application/octet-stream;base64,AA*A!"))
add("gltf_position_accessor_index_invalid.gltf", gltf_doc(pos_accessor=7))
add("gltf_sparse_accessor.gltf", gltf_doc(sparse=True))
add("gltf_node_cycle.gltf", gltf_doc(nodes=[{"mesh": 0, "children": [1]}, {"children": [0]}]))
add("gltf_zero_count_accessor.gltf", gltf_doc(index_count=0))

# ------------------------------------------------------------------ XYZ / PTS

add("xyz_empty.xyz", b"")
add("xyz_non_numeric.xyz", "0 0 0\n1 one 1\n")
add("xyz_two_columns.xyz", "0 0\n1 1\n")
add("xyz_ragged_columns.xyz", "0 0 0\n1 1 1 1 1 1\n")
add("xyz_nan.xyz", "0 0 0\nnan 1 1\n")
add("xyz_inf.xyz", "0 0 0\n1 -inf 1\n")
add("xyz_colour_out_of_range.xyz", "0 0 0 0 0 1 255 256 0\n")
add("pts_count_mismatch.pts", "5\n0 0 0\n1 1 1\n")
add("pts_count_huge.pts", "4000000000\n0 0 0\n")
add("pts_nan.pts", "2\n0 0 0 10 1 2 3\nNaN 1 1 10 1 2 3\n")
add("pts_non_numeric.pts", "1\n0 0 zero\n")
add("pts_count_only.pts", "3\n")

# ------------------------------------------- the reliability probe classes
# ASCII PLY is line-structured: values never run across lines.
add("ply_ascii_values_across_lines.ply",
    ply_header("ascii", 3, 1) + "0 0 0 1\n0 0 0 1\n0 3 0 1 2\n")
add("ply_ascii_too_few_values.ply", ply_header("ascii", 3, 1) + "0 0 0\n1 0\n0 1 0\n3 0 1 2\n")
add("ply_ascii_too_many_values.ply",
    ply_header("ascii", 3, 1) + "0 0 0\n1 0 0 7\n0 1 0\n3 0 1 2\n")
add("ply_ascii_vertex_count_too_small.ply", ply_header("ascii", 2, 1) + TRI_ASCII_BODY)
add("ply_ascii_vertex_count_too_large.ply",
    ply_header("ascii", 4, 1) + TRI_ASCII_BODY + "3 0 1 2\n")
add("ply_ascii_extra_lines.ply", ply_header("ascii", 3, 1) + TRI_ASCII_BODY + "3 2 1 0\n")
add("ply_face_two_indices.ply", ply_header("ascii", 3, 1) + "0 0 0\n1 0 0\n0 1 0\n2 0 1\n")
add("ply_face_two_indices_binary.ply",
    ply_header("binary_little_endian", 3, 1).encode() + ply_bin_tri(faces=((0, 1),)))
# Bytes that would act on a terminal (ESC, BEL) must come out escaped.
add("ply_header_control_chars.ply",
    ply_header("ascii", 3, 1).replace("end_header", "\x1b[31mevil\x07\nend_header")
    + TRI_ASCII_BODY)
# Buffer URIs: percent-decoded, then relative inside the glTF's folder only.
add("gltf_buffer_uri_percent_absolute.gltf", gltf_doc(uri="%2Fetc%2Fpasswd"))
add("gltf_buffer_uri_parent_dir.gltf", gltf_doc(uri="../../../../proc/self/environ"))
add("gltf_buffer_uri_percent_parent_dir.gltf", gltf_doc(uri="%2E%2E/%2E%2E/etc/passwd"))
add("gltf_buffer_uri_file_scheme.gltf", gltf_doc(uri="file:///etc/passwd"))
add("gltf_buffer_uri_percent_file_scheme.gltf", gltf_doc(uri="file%3A%2F%2F%2Fetc%2Fpasswd"))
add("gltf_buffer_uri_device.gltf", gltf_doc(uri="%2Fdev%2Fzero"))


# Instancing is bounded: 1,026 stored vertices placed by 4,100 nodes would
# expand to 4.2M vertices, over max(16 x stored, 4,194,304).
def instancing_bomb(vertices=1026, nodes=4100):
    pos = b"".join(struct.pack("<3f", i % 7, i % 11, i % 13) for i in range(vertices))
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(pos)}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(pos)}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": vertices,
                       "type": "VEC3", "min": [0, 0, 0], "max": [6, 10, 12]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "nodes": [{"children": list(range(1, nodes + 1))}] + [{"mesh": 0}] * nodes,
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    }
    return glb(json.dumps(doc, sort_keys=True, separators=(",", ":")), bin_bytes=pos)


add("glb_instancing_expands_past_limit.glb", instancing_bomb())

# Coordinates beyond +-1e18 (where f32 squared distances overflow) are
# refused by every reader, however they arise.
BIG = 1e30
add("obj_coordinate_beyond_range.obj", f"v 0 0 0\nv {BIG} 0 0\nv 0 1 0\nf 1 2 3\n")
add("ply_coordinate_beyond_range.ply", ply_header("ascii", 3, 1) + f"0 0 0\n1 0 0\n0 {BIG} 0\n3 0 1 2\n")
add("ply_coordinate_beyond_range_binary.ply",
    ply_header("binary_little_endian", 3, 1).encode()
    + ply_bin_tri(verts=((0, 0, 0), (1, 0, 0), (0, 0, -3e38))))
add("stl_binary_coordinate_beyond_range.stl",
    stl_bin(1, [(0, 0, 1, 0, 0, 0, 2e18, 0, 0, 0, 1, 0)]))
add("stl_ascii_coordinate_beyond_range.stl",
    ASCII_TRI.replace("vertex 1 0 0", "vertex 1e20 0 0") + "endsolid t\n")
add("xyz_coordinate_beyond_range.xyz", "0 0 0\n1e19 1 1\n")
add("pts_coordinate_beyond_range.pts", "2\n0 0 0\n1 1 -1e25\n")
add("gltf_coordinate_beyond_range.gltf",
    gltf_doc(bin_bytes=struct.pack("<9f", 0, 0, 0, BIG, 0, 0, 0, 1, 0) + QUAD[36:]))
# A node transform can carry finite positions past the bound.
add("gltf_node_scale_beyond_range.gltf", gltf_doc(nodes=[{"mesh": 0, "scale": [1e20, 1, 1]}]))

# LAS/LAZ: hand-made LAS 1.2 headers (227 bytes, point format 0 of 20
# bytes), each with one field that lies; LAS 1.4 (375 bytes) for EVLRs.
def las_header(points=3, fmt=0, record=20, scale=0.01, version=(1, 2), data_offset=None,
               evlr=None):
    size = 375 if version >= (1, 4) else 227
    offset = size if data_offset is None else data_offset
    h = b"LASF" + struct.pack("<HH", 0, 0) + bytes(16) + bytes(version)
    h += b"lodkit".ljust(32, b"\0") + b"lodkit malformed".ljust(32, b"\0")
    h += struct.pack("<HHHIIBHI", 1, 2024, size, offset, 0, fmt, record, min(points, 2**32 - 1))
    h += struct.pack("<5I", min(points, 2**32 - 1), 0, 0, 0, 0)
    h += struct.pack("<3d", scale, scale, scale) + struct.pack("<3d", 0, 0, 0)
    h += struct.pack("<6d", 1, 0, 1, 0, 1, 0)
    if version >= (1, 4):
        start, count = evlr if evlr else (0, 0)
        h += struct.pack("<QQI", 0, start, count) + struct.pack("<Q", points) + bytes(120)
    assert len(h) == size, len(h)
    return h


def las_points(n):
    return b"".join(struct.pack("<3iHBBbBH", i, 2 * i, 3 * i, 0, 0x11, 0, 0, 0, 0)
                    for i in range(n))


add("las_point_count_huge.las", las_header(points=4000000000) + las_points(3))
add("las_truncated_points.las", las_header(points=3) + las_points(3)[:50])
add("las_zero_scale.las", las_header(scale=0.0) + las_points(3))
add("las_header_cut.las", las_header()[:120])
add("las_no_points.las", las_header(points=0))
# An extended VLR whose u64 length is far past the end of the file.
add("las_evlr_length_huge.las",
    las_header(version=(1, 4), evlr=(375 + 60, 1)) + las_points(3)
    + struct.pack("<H16sHQ32s", 0, b"x", 1, 2**62, b""))
# LAZ (format bit 7): a chunk table claiming four billion chunks.
add("laz_chunk_count_huge.laz",
    las_header(fmt=0x80) + struct.pack("<q", 227 + 8 + 24) + bytes(24)
    + struct.pack("<II", 0, 2**32 - 1))
add("laz_no_laszip_vlr.laz", las_header(fmt=0x80) + struct.pack("<q", -1) + bytes(40))


# .conf: a quaternion that cannot be normalised (its length overflows f32,
# or it is zero or not finite) and far translations are refused by line.
CONF_OK = "camera 0 0 0 0 0 0 1\nbmesh a.ply 0 0 0 0 0 0 1\n"
add("conf_quaternion_overflows.conf", CONF_OK + "bmesh b.ply 0 0 0 3e19 3e19 0 1\n")
add("conf_quaternion_huge_component.conf", CONF_OK + "bmesh b.ply 0 0 0 0 0 1e30 1\n")
add("conf_quaternion_zero.conf", CONF_OK + "bmesh b.ply 0 0 0 0 0 0 0\n")
add("conf_quaternion_nan.conf", CONF_OK + "bmesh b.ply 0 0 0 0 nan 0 1\n")
add("conf_quaternion_inf.conf", CONF_OK + "bmesh b.ply 0 0 0 0 0 0 1e39\n")
add("conf_translation_beyond_range.conf", CONF_OK + "bmesh b.ply 5e18 0 0 0 0 0 1\n")
add("conf_missing_numbers.conf", CONF_OK + "bmesh b.ply 0 0 0 0 0 1\n")


# ------------------------------------------------- materials, images, buffers
def gltf_edit(edit, uri=None, bin_bytes=QUAD):
    """gltf_doc's triangle with `edit(doc)` applied to its JSON."""
    doc = json.loads(gltf_doc(uri=uri, bin_bytes=bin_bytes))
    edit(doc)
    return json.dumps(doc, sort_keys=True)


def with_material(material):
    def edit(doc):
        doc["materials"] = [material]
        doc["meshes"][0]["primitives"][0]["material"] = 0
    return edit


def with_image(image):
    def edit(doc):
        doc["images"] = [image]
        doc["textures"] = [{"source": 0}]
        doc["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]
        doc["meshes"][0]["primitives"][0]["material"] = 0
    return edit


# The gltf crate unwraps an image's source: checked before it is asked.
add("gltf_image_without_uri_or_view.gltf", gltf_edit(with_image({"name": "nothing"})))
add("glb_image_view_without_mime_type.glb",
    glb(gltf_edit(with_image({"bufferView": 0}), uri=False)))
# Factors beyond f32 read as infinity, which JSON cannot hold on writing.
add("gltf_material_factor_1e39.gltf",
    gltf_edit(with_material({"pbrMetallicRoughness": {"baseColorFactor": [1e39, 1, 1, 1]}})))
add("gltf_material_factor_1e300.gltf",
    gltf_edit(with_material({"pbrMetallicRoughness": {"metallicFactor": 1e300}})))
add("gltf_material_emissive_negative.gltf", gltf_edit(with_material({"emissiveFactor": [-1, 0, 0]})))
# A number JSON cannot hold in an extension the gltf crate skips.
add("gltf_texture_transform_scale_1e999.gltf",
    gltf_edit(lambda d: (with_material({"pbrMetallicRoughness": {"baseColorTexture": {
        "index": 0, "extensions": {"KHR_texture_transform": {"scale": [12345, 1]}}}}})(d),
        d.update(textures=[{"source": 0}], images=[{"uri": "t.png"}],
                 extensionsUsed=["KHR_texture_transform"]))).replace("12345", "1e999"))
# Only buffer 0 may stand for the BIN chunk.
add("glb_second_buffer_without_uri.glb",
    glb(gltf_edit(lambda d: (d["buffers"].append({"byteLength": len(QUAD)}),
                             [v.update(buffer=1) for v in d["bufferViews"]]), uri=False)))


# A quantised accessor's offset must be a whole number >= 0, never read as 0.
def quantised(edit_accessor):
    pos = struct.pack("<9H", 0, 0, 0, 1, 0, 0, 0, 1, 0) + b"\0\0" + struct.pack("<3H", 0, 1, 2) + b"\0\0"

    def edit(d):
        d["extensionsUsed"] = ["KHR_mesh_quantization"]
        d["extensionsRequired"] = ["KHR_mesh_quantization"]
        d["bufferViews"] = [{"buffer": 0, "byteOffset": 0, "byteLength": 20},
                            {"buffer": 0, "byteOffset": 20, "byteLength": 6}]
        d["accessors"][0].update(componentType=5123, min=[0, 0, 0], max=[1, 1, 0])
        edit_accessor(d["accessors"][0])
    return gltf_edit(edit, bin_bytes=pos)


add("gltf_quantized_negative_byte_offset.gltf", quantised(lambda a: a.update(byteOffset=-4)))
add("gltf_quantized_fractional_count.gltf", quantised(lambda a: a.update(count=2.5)))


# ------------------------------------------------- scenes: a file and what it names
# tests/malformed/scenes/CASE/ holds an input and the files it names, and
# expect.txt: the input (first line) and the text its one-line error must
# hold (`says: TEXT`); crates/cli/tests/scenes_cli.rs runs them.
SCENES = {}
TRI_OBJ = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n"


def scene(name, files, says, input_name="m.obj"):
    assert name not in SCENES, name
    SCENES[name] = ({k: v.encode() if isinstance(v, str) else v for k, v in files.items()},
                    f"{input_name}\nsays: {says}\n")


scene("mtl_kd_infinite", {"m.obj": TRI_OBJ, "m.mtl": "newmtl a\nKd inf -inf inf\n"}, "Kd")
scene("mtl_ke_beyond_f32", {"m.obj": TRI_OBJ, "m.mtl": "newmtl a\nKd 1 1 1\nKe 1e39 0 0\n"}, "Ke")
scene("mtl_ns_nan", {"m.obj": TRI_OBJ, "m.mtl": "newmtl a\nNs nan\n"}, "Ns")


def main():
    os.makedirs(OUT, exist_ok=True)
    # Remove corpus files this script no longer makes (keep the README).
    for name in os.listdir(OUT):
        path = os.path.join(OUT, name)
        if name != "README.md" and name not in FILES and os.path.isfile(path):
            os.remove(path)
    for name, data in sorted(FILES.items()):
        with open(os.path.join(OUT, name), "wb") as f:
            f.write(data)
    scenes = os.path.join(OUT, "scenes")
    if os.path.isdir(scenes):
        shutil.rmtree(scenes)
    for name, (files, expect) in sorted(SCENES.items()):
        os.makedirs(os.path.join(scenes, name))
        for file, data in sorted(files.items()):
            with open(os.path.join(scenes, name, file), "wb") as f:
                f.write(data)
        with open(os.path.join(scenes, name, "expect.txt"), "w") as f:
            f.write(expect)
    print(f"wrote {len(FILES)} files and {len(SCENES)} scene folders to {OUT}")


if __name__ == "__main__":
    main()
