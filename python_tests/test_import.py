"""File > Import of hair files: TressFX 3 / 4 and Cem Yuksel's .hair, and Sintel's real groom."""
import struct

import bpy
import numpy as np
import pytest

from conftest import ROOT
from hairdyn import bridge, native
from hairdyn.hair_formats import HairFileError, read_cem_hair, read_tfx
from hairdyn.io_import import FIXED_ATTRIBUTE

SINTEL = ROOT.parent / "shared" / "data" / "sintel"


def strands(strands_num=3, points=4):
    rng = np.random.default_rng(5)
    return rng.normal(size=(strands_num, points, 3)).astype(np.float32)


def write_tfx4(path, positions, fixed_per_strand=1):
    strands_num, points, _ = positions.shape
    xyzw = np.ones((strands_num, points, 4), np.float32)
    xyzw[..., :3] = positions
    xyzw[:, :fixed_per_strand, 3] = 0.0
    header = struct.pack("<fII5I", 4.0, strands_num, points, 160, 0, 0, 0, 0) + bytes(160 - 32)
    path.write_bytes(header + xyzw.tobytes())


def write_tfx3(path, positions, both_ends=0):
    strands_num, points, _ = positions.shape
    header = struct.pack("<fIIII", 3.0, strands_num, points, 0, both_ends) + bytes(31 * 4)
    header += struct.pack("<6I", 296, 0, 0, 0, 0, 0) + bytes(32 * 4)
    assert len(header) == 296
    path.write_bytes(header + positions.tobytes())


def write_cem(path, segments, points, thickness=None):
    arrays = 1 | 2 | (4 if thickness is not None else 0)
    header = b"HAIR" + struct.pack("<4I2f3f", len(segments), len(points), arrays, 0, 0.0, 1.0,
                                   0, 0, 0) + bytes(88)
    assert len(header) == 128
    body = np.asarray(segments, np.uint16).tobytes() + np.asarray(points, np.float32).tobytes()
    if thickness is not None:
        body += np.asarray(thickness, np.float32).tobytes()
    path.write_bytes(header + body)


def test_tfx4_and_tfx3(tmp_path):
    positions = strands()
    write_tfx4(tmp_path / "a.tfx", positions, fixed_per_strand=2)
    hair = read_tfx(tmp_path / "a.tfx")
    assert np.array_equal(hair.positions, positions.reshape(-1, 3))
    assert np.array_equal(hair.curve_offsets, [0, 4, 8, 12])
    assert np.array_equal(hair.fixed.reshape(3, 4), [[1, 1, 0, 0]] * 3)
    write_tfx3(tmp_path / "b.tfx", positions, both_ends=1)
    hair = read_tfx(tmp_path / "b.tfx")
    assert np.array_equal(hair.positions, positions.reshape(-1, 3))
    assert np.array_equal(hair.fixed.reshape(3, 4), [[1, 0, 0, 1]] * 3)


def test_cem_hair(tmp_path):
    points = np.arange(7 * 3, dtype=np.float32).reshape(7, 3)
    write_cem(tmp_path / "a.hair", [2, 3], points, thickness=np.full(7, 0.02))
    hair = read_cem_hair(tmp_path / "a.hair")
    assert np.array_equal(hair.curve_offsets, [0, 3, 7])
    assert np.array_equal(hair.positions, points)
    assert np.array_equal(np.flatnonzero(hair.fixed), [0, 3])
    assert np.allclose(hair.thickness, 0.02)


@pytest.mark.parametrize("make, message", [
    (lambda p: p.write_bytes(b"HAIR" + bytes(10)), "not a .hair file"),
    (lambda p: write_cem(p, [2, 3], np.zeros((6, 3))), "says 6 points but its 2 strands have 7"),
    (lambda p: p.write_bytes(b"HAIR" + struct.pack("<4I", 2, 8, 2, 3) + bytes(108 + 10)),
     r"bad.hair' is truncated: its points need bytes"),
])
def test_bad_cem_hair(tmp_path, make, message):
    path = tmp_path / "bad.hair"
    make(path)
    with pytest.raises(HairFileError, match=message):
        read_cem_hair(path)


def test_bad_tfx(tmp_path):
    path = tmp_path / "bad.tfx"
    write_tfx4(path, strands())
    path.write_bytes(path.read_bytes()[:-8])
    with pytest.raises(HairFileError, match=r"bad.tfx' is truncated: its positions need bytes"):
        read_tfx(path)
    path.write_bytes(struct.pack("<fII", 2.0, 3, 4) + bytes(400))
    with pytest.raises(HairFileError, match="TressFX version 2; hairdyn reads 3.0 and 4.0"):
        read_tfx(path)


def test_import_operator_makes_curves(tmp_path, empty_scene):
    positions = strands()
    write_tfx4(tmp_path / "groom.tfx", positions)
    assert bpy.ops.hairdyn.import_tfx(filepath=str(tmp_path / "groom.tfx")) == {'FINISHED'}
    obj = bpy.context.view_layer.objects.active
    assert obj.name == "groom" and obj.type == 'CURVES'
    groom = bridge.read_curves(obj, bpy.context.evaluated_depsgraph_get())
    flat = positions.reshape(-1, 3)
    assert np.allclose(groom.positions_wo, np.c_[flat[:, 0], -flat[:, 2], flat[:, 1]])
    fixed = np.empty(12, bool)
    obj.data.attributes[FIXED_ATTRIBUTE].data.foreach_get("value", fixed)
    assert np.array_equal(fixed.reshape(3, 4)[:, 0], [True] * 3)
    assert not fixed.reshape(3, 4)[:, 1:].any()
    (tmp_path / "broken.tfx").write_bytes(b"\x00\x00")
    with pytest.raises(RuntimeError, match="too short to be a TressFX file"):
        bpy.ops.hairdyn.import_tfx(filepath=str(tmp_path / "broken.tfx"))


def test_sintel_hair_sits_on_sintel_bust(empty_scene):
    if not SINTEL.is_dir():
        pytest.skip(f"needs the Sintel assets in {SINTEL}")
    assert bpy.ops.hairdyn.import_tfx(filepath=str(SINTEL / "sintel_hair.tfx")) == {'FINISHED'}
    hair = bpy.context.view_layer.objects.active
    if hasattr(bpy.ops.wm, "obj_import"):
        bpy.ops.wm.obj_import(filepath=str(SINTEL / "sintel_bust.obj"))
    else:
        bpy.ops.import_scene.obj(filepath=str(SINTEL / "sintel_bust.obj"))
    bust = next(o for o in bpy.context.scene.objects if o.type == 'MESH')
    graph = bpy.context.evaluated_depsgraph_get()
    groom = bridge.read_curves(hair, graph)
    assert groom.curves_num == 228 and groom.points_num == 228 * 32
    mesh = bridge.read_mesh(bust, graph)
    assert len(mesh.vertices) == 3046 and len(mesh.triangles) == 5952
    vertices = mesh.vertices_wo()
    assert vertices[:, 2].max() - vertices[:, 2].min() > 20  # Z is up after the import
    roots = groom.positions_wo[groom.curve_offsets[:-1]]
    nearest = np.min(np.linalg.norm(vertices[None] - roots[:, None], axis=2), axis=1)
    assert np.median(nearest) < 1.0 and nearest.max() < 2.5


def hanging_strands(strands_num=20, points=8, length=0.2):
    """Strands hanging from roots on a 10 cm patch: a groom about 0.3 m across (metres)."""
    rng = np.random.default_rng(9)
    roots = np.c_[rng.uniform(-0.05, 0.05, strands_num), np.zeros(strands_num),
                  rng.uniform(-0.05, 0.05, strands_num)]
    t = np.linspace(0.0, 1.0, points)[None, :, None]
    return (roots[:, None, :] - t * np.array([0.0, length, 0.0])).astype(np.float32)


def test_tiny_strands_are_kept_and_zero_length_ones_dropped_with_a_warning(tmp_path, empty_scene):
    """Real TressFX assets carry strands of a few µm (Ratboy: 7.5 µm; bear at scale 0.01:
    2 µm): such a strand is simulable when its segments are long against the groom's size (the
    tolerance is a millionth of it, 0.3 µm here); one whose points coincide is left out, and the
    import says how many."""
    positions = hanging_strands()
    positions[3] = positions[3, :1] + np.linspace(0.0, 7.5e-6, 8)[:, None] * [1.0, 0.0, 0.0]
    positions[11] = positions[11, :1]  # every point on the root: no direction at all
    write_tfx4(tmp_path / "groom.tfx", positions)
    assert bpy.ops.hairdyn.import_tfx(filepath=str(tmp_path / "groom.tfx")) == {'FINISHED'}
    obj = bpy.context.view_layer.objects.active
    assert len(obj.data.curves) == 19 and len(obj.data.points) == 19 * 8
    groom = bridge.read_curves(obj, bpy.context.evaluated_depsgraph_get())
    native.load().validate_groom(groom.curve_offsets, groom.positions_wo)  # 7.5 µm: accepted
    from hairdyn.io_import import create_hair_object

    warnings = []
    create_hair_object(bpy.context, "again", read_tfx(tmp_path / "groom.tfx"), warnings=warnings)
    assert any(w.startswith("1 strands with a zero-length segment") for w in warnings)


def test_implausible_groom_sizes_are_warned_about(tmp_path, empty_scene):
    from hairdyn.io_import import create_hair_object

    write_tfx4(tmp_path / "groom.tfx", hanging_strands() * 500.0)  # TressFX units: 150 m
    for scale, expect in ((1.0, "more than hair usually is"), (0.002, None),
                          (1e-5, "less than hair usually is")):
        warnings = []
        create_hair_object(bpy.context, "g", read_tfx(tmp_path / "groom.tfx"), scale=scale,
                           warnings=warnings)
        size_notes = [w for w in warnings if "across" in w]
        if expect is None:
            assert not size_notes
        else:
            assert size_notes and expect in size_notes[0]


def cap_groom(radius, strands_num=60, points=6, length=None, max_polar=1.2):
    """Strands growing outward from roots on the top of a sphere of `radius` centred at the
    origin (Blender axes), as a Y-up file holds them: (x, y, z) -> (x, z, -y)."""
    rng = np.random.default_rng(3)
    polar = np.arccos(rng.uniform(np.cos(max_polar), 1.0, strands_num))
    azimuth = rng.uniform(0.0, 2.0 * np.pi, strands_num)
    normals = np.c_[np.sin(polar) * np.cos(azimuth), np.sin(polar) * np.sin(azimuth),
                    np.cos(polar)]
    t = np.linspace(0.0, length or 2.0 * radius, points)[None, :, None]
    blender = normals[:, None, :] * (radius + t)
    return np.ascontiguousarray(blender[..., [0, 2, 1]] * [1.0, 1.0, -1.0]).astype(np.float32)


def head_and_shoulders(center, radius):
    """One mesh: a UV sphere head of `radius` at `center` on a box of shoulders 4 heads wide
    below it (the fit must find the head, not the body's width)."""
    bpy.ops.mesh.primitive_uv_sphere_add(radius=radius, location=center, segments=64,
                                         ring_count=32)
    head = bpy.context.active_object
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(center[0], center[1],
                                                         center[2] - 2.2 * radius))
    body = bpy.context.active_object
    body.scale = (4.0 * radius, 1.5 * radius, 2.0 * radius)
    for obj in (head, body):
        obj.select_set(True)
    bpy.context.view_layer.objects.active = head
    bpy.ops.object.join()
    head.name = "Body"
    return head


@pytest.mark.parametrize("file_radius", [9.0, 0.09, 1800.0])
def test_fit_to_object_puts_the_roots_on_the_head_whatever_the_units(tmp_path, empty_scene,
                                                                      file_radius):
    """Issue 11 row 11: a groom in unknown units (centimetres, metres, TressFX's hundreds of
    units) lands on a 10 cm head standing at (1, 2, 1.5) on shoulders: the scale the file
    needs and the roots on the scalp."""
    center, radius = (1.0, 2.0, 1.5), 0.1
    body = head_and_shoulders(center, radius)
    write_tfx4(tmp_path / "groom.tfx", cap_groom(file_radius))
    assert bpy.ops.hairdyn.import_tfx(filepath=str(tmp_path / "groom.tfx"),
                                      fit_to=body.name) == {'FINISHED'}
    hair = bpy.context.view_layer.objects.active
    assert hair.type == 'CURVES'
    assert hair["hairdyn_import_scale"] == pytest.approx(radius / file_radius, rel=0.03)
    groom = bridge.read_curves(hair, bpy.context.evaluated_depsgraph_get())
    roots = groom.positions_wo[groom.curve_offsets[:-1]]
    gap = np.abs(np.linalg.norm(roots - center, axis=1) - radius)
    found = hair["hairdyn_import_scale"] * file_radius / radius
    print(f"scale {found:.4f} of the true one, root gap median {np.median(gap) * 1e3:.3f} mm, "
          f"max {gap.max() * 1e3:.3f} mm")
    assert np.median(gap) < 1e-3 and gap.max() < 3e-3


def test_fit_to_object_refuses_what_is_not_a_mesh(tmp_path, empty_scene):
    write_tfx4(tmp_path / "groom.tfx", cap_groom(9.0))
    bpy.ops.object.empty_add()
    with pytest.raises(RuntimeError, match="is not a mesh object"):
        bpy.ops.hairdyn.import_tfx(filepath=str(tmp_path / "groom.tfx"),
                                   fit_to=bpy.context.active_object.name)
    assert not [o for o in bpy.data.objects if o.type == 'CURVES']


def test_sintel_hair_fits_on_sintel_bust_from_other_units(empty_scene):
    """The real groom, imported as if in other units (× 0.37), fitted to the real bust: it
    comes back to where it sits at scale 1 (the file's units are the bust's)."""
    if not SINTEL.is_dir():
        pytest.skip(f"needs the Sintel assets in {SINTEL}")
    if hasattr(bpy.ops.wm, "obj_import"):
        bpy.ops.wm.obj_import(filepath=str(SINTEL / "sintel_bust.obj"))
    else:
        bpy.ops.import_scene.obj(filepath=str(SINTEL / "sintel_bust.obj"))
    bust = next(o for o in bpy.context.scene.objects if o.type == 'MESH')
    assert bpy.ops.hairdyn.import_tfx(filepath=str(SINTEL / "sintel_hair.tfx"), scale=0.37,
                                      fit_to=bust.name) == {'FINISHED'}
    hair = bpy.context.view_layer.objects.active
    print(f"Sintel fitted at scale {hair['hairdyn_import_scale']:.4f}")
    assert hair["hairdyn_import_scale"] == pytest.approx(1.0, rel=0.05)
