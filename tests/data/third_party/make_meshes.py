#!/usr/bin/env python3
"""Writes the meshes of the iiwa_like_description test package (standard library only).

The meshes are simple closed cylinders; what matters for the tests is the way each file is
written, as third-party ROS packages do it:
  meshes/visual/base.dae       COLLADA in millimetres (<unit meter="0.001"/>, Z_UP), a node translation
  meshes/visual/segment.dae    COLLADA in millimetres, two sub-meshes under two nodes
  meshes/visual/wrist.obj      Wavefront OBJ in metres (quads, to exercise triangulation)
  meshes/collision/base.stl    binary STL in metres
  meshes/collision/segment_mm.stl  binary STL in millimetres (the URDF scales it by 0.001)
  meshes/collision/wrist.stl   ASCII STL in metres
  meshes/collision/truncated.stl   a binary STL cut short (for the failure test)
Regenerate with:  python3 tests/data/third_party/make_meshes.py
"""
import math
import os
import struct

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "iiwa_like_description", "meshes")
N = 24  # segments around


def cylinder(radius, z0, z1, n=N):
    """Closed cylinder about z: vertex list and quads/triangles wound counter-clockwise outside."""
    verts = []
    for z in (z0, z1):
        for j in range(n):
            a = 2 * math.pi * j / n
            verts.append((radius * math.cos(a), radius * math.sin(a), z))
    bottom_centre = len(verts)
    verts.append((0.0, 0.0, z0))
    top_centre = len(verts)
    verts.append((0.0, 0.0, z1))
    quads, tris = [], []
    for j in range(n):
        k = (j + 1) % n
        quads.append((j, k, n + k, n + j))
        tris.append((bottom_centre, k, j))
        tris.append((top_centre, n + j, n + k))
    return verts, quads, tris


def triangles(verts, quads, tris):
    out = [t for t in tris]
    for a, b, c, d in quads:
        out.append((a, b, c))
        out.append((a, c, d))
    return out


def write_binary_stl(path, verts, faces, scale=1.0, truncate_to=None):
    data = bytearray(b"iiwa_like_description test mesh".ljust(80, b" "))
    data += struct.pack("<I", len(faces))
    for f in faces:
        p = [tuple(scale * x for x in verts[i]) for i in f]
        u = [p[1][i] - p[0][i] for i in range(3)]
        v = [p[2][i] - p[0][i] for i in range(3)]
        n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
        length = math.sqrt(sum(x * x for x in n)) or 1.0
        data += struct.pack("<3f", *(x / length for x in n))
        for q in p:
            data += struct.pack("<3f", *q)
        data += struct.pack("<H", 0)
    if truncate_to is not None:
        data = data[:truncate_to]
    with open(path, "wb") as out:
        out.write(bytes(data))


def write_ascii_stl(path, verts, faces):
    lines = ["solid wrist"]
    for f in faces:
        p = [verts[i] for i in f]
        lines.append("  facet normal 0 0 0")
        lines.append("    outer loop")
        for q in p:
            lines.append("      vertex %.6f %.6f %.6f" % q)
        lines.append("    endloop")
        lines.append("  endfacet")
    lines.append("endsolid wrist")
    with open(path, "w") as out:
        out.write("\n".join(lines) + "\n")


def write_obj(path, verts, quads, tris):
    lines = ["# iiwa_like_description wrist, metres"]
    lines += ["v %.6f %.6f %.6f" % v for v in verts]
    lines += ["f " + " ".join(str(i + 1) for i in f) for f in quads + tris]
    with open(path, "w") as out:
        out.write("\n".join(lines) + "\n")


def dae_geometry(gid, verts, faces):
    positions = " ".join("%.4f %.4f %.4f" % v for v in verts)
    indices = " ".join(str(i) for f in faces for i in f)
    return f"""    <geometry id="{gid}" name="{gid}">
      <mesh>
        <source id="{gid}-positions">
          <float_array id="{gid}-positions-array" count="{3 * len(verts)}">{positions}</float_array>
          <technique_common>
            <accessor source="#{gid}-positions-array" count="{len(verts)}" stride="3">
              <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
            </accessor>
          </technique_common>
        </source>
        <vertices id="{gid}-vertices"><input semantic="POSITION" source="#{gid}-positions"/></vertices>
        <triangles count="{len(faces)}">
          <input semantic="VERTEX" source="#{gid}-vertices" offset="0"/>
          <p>{indices}</p>
        </triangles>
      </mesh>
    </geometry>
"""


def write_dae(path, parts):
    """parts: list of (id, verts, faces, (tx, ty, tz)) in millimetres."""
    geometries = "".join(dae_geometry(gid, v, f) for gid, v, f, _ in parts)
    nodes = "".join(
        f"""      <node id="{gid}-node" name="{gid}">
        <translate>{t[0]} {t[1]} {t[2]}</translate>
        <instance_geometry url="#{gid}"/>
      </node>
""" for gid, _, _, t in parts)
    text = f"""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset>
    <contributor><authoring_tool>make_meshes.py</authoring_tool></contributor>
    <unit name="millimeter" meter="0.001"/>
    <up_axis>Z_UP</up_axis>
  </asset>
  <library_geometries>
{geometries}  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene" name="scene">
{nodes}    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
"""
    with open(path, "w") as out:
        out.write(text)


def main():
    os.makedirs(os.path.join(ROOT, "visual"), exist_ok=True)
    os.makedirs(os.path.join(ROOT, "collision"), exist_ok=True)
    # Base: radius 110 mm, 0..157.5 mm, written from -78.75..78.75 and moved up by a node
    # translation of 78.75 mm.
    v, q, t = cylinder(110.0, -78.75, 78.75)
    write_dae(os.path.join(ROOT, "visual", "base.dae"), [("base", v, triangles(v, q, t), (0, 0, 78.75))])
    # Segment: a 200 mm long body of radius 65 mm (two sub-meshes of 100 mm under two nodes).
    v, q, t = cylinder(65.0, 0.0, 100.0)
    faces = triangles(v, q, t)
    write_dae(os.path.join(ROOT, "visual", "segment.dae"),
              [("lower", v, faces, (0, 0, 0)), ("upper", v, faces, (0, 0, 100))])
    # Wrist: radius 0.05 m, 0..0.081 m, metres.
    v, q, t = cylinder(0.05, 0.0, 0.081)
    write_obj(os.path.join(ROOT, "visual", "wrist.obj"), v, q, t)
    write_ascii_stl(os.path.join(ROOT, "collision", "wrist.stl"), v, triangles(v, q, t))
    v, q, t = cylinder(0.11, 0.0, 0.1575, 12)
    write_binary_stl(os.path.join(ROOT, "collision", "base.stl"), v, triangles(v, q, t))
    v, q, t = cylinder(65.0, 0.0, 200.0, 12)
    write_binary_stl(os.path.join(ROOT, "collision", "segment_mm.stl"), v, triangles(v, q, t))
    write_binary_stl(os.path.join(ROOT, "collision", "truncated.stl"), v, triangles(v, q, t), truncate_to=84 + 50 * 10 + 17)


if __name__ == "__main__":
    main()
