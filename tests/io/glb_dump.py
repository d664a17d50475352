#!/usr/bin/env python3
"""Prints what the glb tests check, read with Python's own json and struct
(independently of the C++ writer): usage glb_dump.py FILE.glb

  nodes N
  scene i j ...                      root nodes of scene 0
  node i mesh tx ty tz | rx ry rz rw | name   (empty between bars when absent)
  mesh i material vertex_count
  material i double_sided r g b a
  channel node path key_count interpolation
  key t v...                         one per key of the channel above (not for weights)
"""
import json
import struct
import sys

data = open(sys.argv[1], "rb").read()
magic, version, length = struct.unpack_from("<III", data, 0)
assert magic == 0x46546C67 and version == 2 and length == len(data), "bad GLB header"
json_len, json_type = struct.unpack_from("<II", data, 12)
assert json_type == 0x4E4F534A, "first chunk is not JSON"
gltf = json.loads(data[20:20 + json_len])
bin_len, bin_type = struct.unpack_from("<II", data, 20 + json_len)
assert bin_type == 0x004E4942, "second chunk is not BIN"
binary = data[28 + json_len:28 + json_len + bin_len]


def accessor(i):
    a = gltf["accessors"][i]
    view = gltf["bufferViews"][a["bufferView"]]
    n = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[a["type"]]
    assert a["componentType"] == 5126, "expected float32"
    offset = view.get("byteOffset", 0) + a.get("byteOffset", 0)
    values = struct.unpack_from("<%df" % (n * a["count"]), binary, offset)
    return [values[k * n:(k + 1) * n] for k in range(a["count"])]


print("nodes", len(gltf["nodes"]))
print("scene", *gltf["scenes"][gltf.get("scene", 0)]["nodes"])
for i, node in enumerate(gltf["nodes"]):
    print("node", i, node["mesh"], *node.get("translation", []), "|", *node.get("rotation", []), "|", node["name"])
for i, mesh in enumerate(gltf["meshes"]):
    p = mesh["primitives"][0]
    print("mesh", i, p["material"], gltf["accessors"][p["attributes"]["POSITION"]]["count"])
for i, m in enumerate(gltf.get("materials", [])):
    print("material", i, int(m.get("doubleSided", False)), *m["pbrMetallicRoughness"]["baseColorFactor"])
for anim in gltf.get("animations", []):
    for c in anim["channels"]:
        s = anim["samplers"][c["sampler"]]
        times, values = accessor(s["input"]), accessor(s["output"])
        print("channel", c["target"]["node"], c["target"]["path"], len(times), s["interpolation"])
        if c["target"]["path"] != "weights":
            for t, v in zip(times, values):
                print("key", *t, *v)
