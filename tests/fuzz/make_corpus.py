#!/usr/bin/env python3
"""Writes the fuzz targets' seed corpora under tests/fuzz/corpus/<target>/.

Seeds are small, made here, and cover each format's variants (ASCII and binary, both byte orders,
indexed and inline, with and without materials, buffers and textures). The .tws and package seeds
are written by the terawalk binary given as the first argument (`build/rel/tools/terawalk`); the
STEP seed was written by OpenCASCADE 7.6 (STEPControl_Writer, a 20 x 10 x 5 box minus a
cylinder) and is kept as it is. Run from the repository root; outputs are committed.
"""
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus")
TETRA = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]
FACES = [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)]


def put(target, name, data):
    folder = os.path.join(ROOT, target)
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def ply_seeds():
    header = ("ply\nformat {fmt} 1.0\ncomment seed\nelement vertex 4\nproperty float x\n"
              "property float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
              "property uchar blue\nelement face 4\nproperty list uchar int vertex_indices\n"
              "end_header\n")
    text = header.format(fmt="ascii")
    text += "".join(f"{x} {y} {z} 200 10 10\n" for x, y, z in TETRA)
    text += "".join(f"3 {a} {b} {c}\n" for a, b, c in FACES)
    put("ply", "tetra-ascii.ply", text)
    for fmt, order in (("binary_little_endian", "<"), ("binary_big_endian", ">")):
        body = b"".join(struct.pack(order + "fffBBB", x, y, z, 10, 200, 10) for x, y, z in TETRA)
        body += b"".join(struct.pack(order + "Biii", 3, a, b, c) for a, b, c in FACES)
        put("ply", f"tetra-{fmt}.ply", header.format(fmt=fmt).encode() + body)


def obj_seeds():
    obj = ("mtllib m.mtl\no tetra\n" + "".join(f"v {x} {y} {z}\n" for x, y, z in TETRA) +
           "vn 0 0 1\nvt 0 0\nusemtl red\nf 1 3 2\nf 1/1/1 2/1/1 4/1/1\ng second\n"
           "usemtl blue\nf 2//1 3//1 4//1\nf -4 -1 -2\n")
    mtl = "newmtl red\nKd 1 0 0\nd 1\nnewmtl blue\nKd 0 0 1\nTr 0.5\n"
    put("obj", "tetra-mtl.obj", obj + "\0" + mtl)
    put("obj", "quad-no-mtl.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")


def stl_seeds():
    facets = "".join(
        "facet normal 0 0 1\n outer loop\n" +
        "".join(f"  vertex {TETRA[i][0]} {TETRA[i][1]} {TETRA[i][2]}\n" for i in face) +
        " endloop\nendfacet\n" for face in FACES)
    put("stl", "tetra-ascii.stl", "solid tetra\n" + facets + "endsolid tetra\n")
    body = struct.pack("<80sI", b"binary seed", len(FACES))
    for face in FACES:
        body += struct.pack("<fff", 0, 0, 1)
        for i in face:
            body += struct.pack("<fff", *TETRA[i])
        body += struct.pack("<H", 0)
    put("stl", "tetra-binary.stl", body)


def gltf_document(uri):
    positions = b"".join(struct.pack("<fff", *p) for p in TETRA)
    indices = b"".join(struct.pack("<HHH", *f) for f in FACES)
    buffer = positions + indices
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "tetra", "mesh": 0, "translation": [1, 2, 3],
                   "children": [1]}, {"name": "child", "mesh": 0, "scale": [2, 2, 2]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1,
                                    "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.1, 0.1, 1]}}],
        "buffers": [{"byteLength": len(buffer)}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(positions)},
                        {"buffer": 0, "byteOffset": len(positions), "byteLength": len(indices)}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 1]},
                      {"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"}],
    }
    if uri:
        doc["buffers"][0]["uri"] = uri
    return doc, buffer


def gltf_seeds():
    doc, buffer = gltf_document("b.bin")
    put("gltf", "tetra-external.gltf", json.dumps(doc).encode() + b"\0" + buffer)
    import base64
    doc, buffer = gltf_document("data:application/octet-stream;base64," +
                                base64.b64encode(buffer).decode())
    put("gltf", "tetra-data-uri.gltf", json.dumps(doc))
    doc, buffer = gltf_document(None)
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    buffer += b"\0" * (-len(buffer) % 4)
    glb = struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(text) + 8 + len(buffer))
    glb += struct.pack("<II", len(text), 0x4E4F534A) + text
    glb += struct.pack("<II", len(buffer), 0x004E4942) + buffer
    put("glb", "tetra.glb", glb)


def camera_path_seeds():
    put("camera_path", "orbit.path",
        "# terawalk camera path 1\n# a comment\n\n0 10 0 2 180 -10 60\n"
        "0.5 7.0710678118654755 7.0710678118654755 2 225 -10 60\n1 0 10 2 270 -12.5 55\n")


def preprocess_plan_seeds():
    # What `preprocess plan` writes, with an excluded layer so every field has a value.
    options = {"cad_conforming_bspline": True, "cad_primitives": True, "cad_tolerance_m": 0.0,
               "cluster_size": 256, "database": "", "exclude_layers": ["hull"],
               "inputs": ["/data/plant.tws"], "max_brick_triangles": 100000,
               "memory_budget_bytes": 2147483648, "parametric_cluster_size": 64,
               "parametric_occluders": True, "up": "auto", "view_cell_size_m": 0.0,
               "visibility": True, "visibility_rays": 1024}
    manifest = {"bricks": [{"index": 1, "triangles": 75935}, {"index": 0, "triangles": 63403}],
                "format": "terawalk preprocess plan", "input_triangles": 495264,
                "objects": 10940, "options": options, "primitives": 10889,
                "run_hash": "5c1f0e2d9a8b7c6d", "version": 1}
    put("preprocess_plan", "plant.json", json.dumps(manifest, indent=2) + "\n")


BCF_MARKUP = """<?xml version="1.0" encoding="UTF-8"?>
<Markup><Header><Files><File IfcProject="2SugUv4EX5LAhcVpDp2dUH"><Filename>a.ifc</Filename></File>
</Files></Header><Topic Guid="11111111-2222-4333-8444-555555555555" TopicType="Issue"
TopicStatus="Open"><Title>Seed</Title><Index>1</Index><Labels><Label>l</Label></Labels>
<CreationDate>2026-01-01T00:00:00Z</CreationDate><CreationAuthor>a</CreationAuthor>
<Comments><Comment Guid="21111111-2222-4333-8444-555555555555"><Date>2026-01-01T00:00:00Z</Date>
<Author>a</Author><Comment>c</Comment><Viewpoint Guid="31111111-2222-4333-8444-555555555555"/>
</Comment></Comments><Viewpoints><ViewPoint Guid="31111111-2222-4333-8444-555555555555">
<Viewpoint>v.bcfv</Viewpoint><Snapshot>s.png</Snapshot><Index>0</Index></ViewPoint></Viewpoints>
</Topic></Markup>
"""
BCF_VISINFO = """<?xml version="1.0" encoding="UTF-8"?>
<VisualizationInfo Guid="31111111-2222-4333-8444-555555555555"><Components>
<Selection><Component IfcGuid="1E8YkwPMfB$h99jtn_uAjI"/></Selection>
<Visibility DefaultVisibility="false"><ViewSetupHints SpacesVisible="false"/><Exceptions>
<Component><OriginatingSystem>TeraWalk</OriginatingSystem><AuthoringToolId>P-1</AuthoringToolId>
</Component></Exceptions></Visibility><Coloring><Color Color="FF8000"><Components>
<Component IfcGuid="1BGpia0iv9cfH1lqT0_P80"/></Components></Color></Coloring></Components>
<PerspectiveCamera><CameraViewPoint><X>1</X><Y>2</Y><Z>3</Z></CameraViewPoint>
<CameraDirection><X>0</X><Y>1</Y><Z>0</Z></CameraDirection><CameraUpVector><X>0</X><Y>0</Y>
<Z>1</Z></CameraUpVector><FieldOfView>60</FieldOfView><AspectRatio>1.5</AspectRatio>
</PerspectiveCamera><ClippingPlanes><ClippingPlane><Location><X>0</X><Y>0</Y><Z>1</Z></Location>
<Direction><X>0</X><Y>0</Y><Z>1</Z></Direction></ClippingPlane></ClippingPlanes>
</VisualizationInfo>
"""


def bcf_seeds():
    """A BCF 3.0 archive (markup, visualisation, snapshot), and its two documents alone."""
    import io
    import zipfile
    buffer = io.BytesIO()
    folder = "11111111-2222-4333-8444-555555555555/"
    entries = [("bcf.version", '<Version VersionId="3.0"/>'), (folder + "markup.bcf", BCF_MARKUP),
               (folder + "v.bcfv", BCF_VISINFO),
               (folder + "s.png", b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR\0\0\0\x02\0\0\0\x01")]
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in entries:  # a fixed date, so the seed is the same every time
            z.writestr(zipfile.ZipInfo(name, (2026, 1, 1, 0, 0, 0)), data, zipfile.ZIP_DEFLATED)
    put("bcf", "topic-3.0.bcfzip", buffer.getvalue())
    put("bcf", "markup.xml", BCF_MARKUP)
    put("bcf", "visinfo.xml", BCF_VISINFO)


def copy_shared(target, source, name):
    folder = os.path.join(ROOT, target)
    os.makedirs(folder, exist_ok=True)
    shutil.copyfile(source, os.path.join(folder, name))


def terawalk_seeds(terawalk):
    with tempfile.TemporaryDirectory() as tmp:
        def run(*args):
            subprocess.run([terawalk, "-q", *args], check=True, cwd=tmp,
                           stdout=subprocess.DEVNULL)
        obj = os.path.join(tmp, "tetra.obj")
        with open(obj, "w") as f:
            f.write("".join(f"v {x} {y} {z}\n" for x, y, z in TETRA))
            f.write("".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in FACES))
        run("preprocess", "tetra.obj", "-o", "tetra.twk")
        run("preprocess", "tetra.obj", "-o", "tetra-cells.twk", "--view-cell-size", "0.5",
            "--visibility-rays", "16")
        copy_shared("package", os.path.join(tmp, "tetra.twk"), "tetra.twk")
        copy_shared("package", os.path.join(tmp, "tetra-cells.twk"), "tetra-cells.twk")
        run("gen", "plant", "--triangles", "1K", "-o", "plant.tws", "--no-db")
        copy_shared("tws", os.path.join(tmp, "plant.tws"), "plant-1k.tws")


if __name__ == "__main__":
    ply_seeds()
    obj_seeds()
    stl_seeds()
    gltf_seeds()
    camera_path_seeds()
    preprocess_plan_seeds()
    bcf_seeds()
    if len(sys.argv) > 1:
        terawalk_seeds(os.path.abspath(sys.argv[1]))
