"""Blender <-> numpy <-> C++: reading hair and meshes, writing results back."""
import math

import bpy
import numpy as np
import pytest
from mathutils import Vector

from hairdyn import bridge, export, native, simulation
from hairdyn.errors import HairdynError


def depsgraph():
    return bpy.context.evaluated_depsgraph_get()


def reference_curves_world(obj):
    """Blender's own evaluated points, one by one through mathutils (slow, independent)."""
    evaluated = obj.evaluated_get(depsgraph())
    matrix = evaluated.matrix_world
    points = [matrix @ Vector(p.position) for p in evaluated.data.points]
    offsets = [c.first_point_index for c in evaluated.data.curves] + [len(points)]
    return np.array(points, dtype=np.float64), np.array(offsets)


def test_read_curves_matches_blender(open_fixture):
    open_fixture("head_curves.blend")
    hair = bpy.data.objects["Hair"]
    groom = bridge.read_curves(hair, depsgraph())
    expected_positions, expected_offsets = reference_curves_world(hair)
    assert groom.positions_wo.dtype == np.float32 and groom.positions_wo.flags.c_contiguous
    assert groom.curve_offsets.dtype == np.int32
    assert np.array_equal(groom.curve_offsets, expected_offsets)
    assert groom.curves_num == 300 and groom.points_num == 2700
    assert np.abs(groom.positions_wo - expected_positions).max() < 1e-6
    assert groom.surface == bpy.data.objects["Body"]
    assert groom.root_uvs.shape == (300, 2)
    assert np.all((groom.root_uvs >= 0.0) & (groom.root_uvs <= 1.0))
    assert len(np.unique(groom.root_uvs, axis=0)) > 250  # real UVs, not a constant


def test_read_curves_is_world_space(open_fixture):
    open_fixture("head_shake.blend")
    bpy.context.scene.frame_set(12)  # the head is turned 35 degrees and moved
    hair = bpy.data.objects["Hair"]
    groom = bridge.read_curves(hair, depsgraph())
    expected_positions, _ = reference_curves_world(hair)
    assert np.abs(groom.positions_wo - expected_positions).max() < 1e-6
    local = np.array([p.position for p in hair.data.points])
    assert np.abs(groom.positions_wo - local).max() > 0.01  # the transform was applied


def test_particle_hair_equals_evaluated_keys(open_fixture):
    open_fixture("head_particles.blend")
    body = bpy.data.objects["Body"]
    psys_settings = body.particle_systems[0].settings
    assert not psys_settings.use_parent_particles
    groom = bridge.read_particle_hair(body, depsgraph())

    evaluated = body.evaluated_get(depsgraph())
    psys = evaluated.particle_systems[0]
    strands_num = len(psys.particles)
    steps = 2 ** psys.settings.display_step + 1
    expected = np.array([[tuple(psys.co_hair(object=evaluated, particle_no=i, step=k))
                          for k in range(steps)] for i in range(strands_num)])
    assert groom.curves_num == strands_num == 300
    assert np.array_equal(np.diff(groom.curve_offsets), np.full(strands_num, steps))
    assert np.abs(groom.positions_wo.reshape(strands_num, steps, 3) - expected).max() < 1e-5
    assert groom.surface == body
    # The user's settings are as they were, and no temporary object is left behind.
    assert not psys_settings.use_parent_particles
    assert sorted(o.name for o in bpy.data.objects) == ["Body", "Camera", "Sun"]
    assert len(bpy.data.hair_curves) == 0


@pytest.mark.parametrize("change", ["children", "another system active"])
def test_particle_hair_reads_the_parents_whatever_is_shown_and_puts_the_settings_back(
        open_fixture, change):
    """read_particle_hair switches on the parents' display (children hide them) and makes the
    hair system the active one only when it must, and puts both back."""
    open_fixture("head_particles.blend")
    body = bpy.data.objects["Body"]
    expected = bridge.read_particle_hair(body, depsgraph())
    settings = body.particle_systems[0].settings
    if change == "children":
        settings.child_type = 'INTERPOLATED'
    else:
        with bpy.context.temp_override(object=body):
            bpy.ops.object.particle_system_add()
        assert body.particle_systems.active_index == 1
    groom = bridge.read_particle_hair(body, depsgraph())
    assert np.array_equal(groom.curve_offsets, expected.curve_offsets)
    assert np.abs(groom.positions_wo - expected.positions_wo).max() < 1e-6
    assert not settings.use_parent_particles
    assert body.particle_systems.active_index == (0 if change == "children" else 1)
    assert len(bpy.data.hair_curves) == 0


def test_read_collider_mesh(open_fixture):
    open_fixture("head_shake.blend")
    body = bpy.data.objects["Body"]
    rest = bridge.read_mesh(body, depsgraph())
    mesh = body.evaluated_get(depsgraph()).data
    mesh.calc_loop_triangles()
    assert rest.triangles.shape == (len(mesh.loop_triangles), 3)
    assert rest.vertices.shape == (len(mesh.vertices), 3)
    assert rest.triangles.dtype == np.int32 and rest.vertices.dtype == np.float32
    for index in (0, 100, len(mesh.vertices) - 1):
        expected = body.matrix_world @ mesh.vertices[index].co
        assert np.allclose(rest.vertices_wo()[index], expected, atol=1e-6)
        expected_normal = (body.matrix_world.to_3x3().inverted().transposed()
                           @ mesh.vertices[index].normal).normalized()
        assert np.allclose(rest.normals_wo()[index], expected_normal, atol=1e-5)
    # Rigid motion is a transform, not new geometry.
    bpy.context.scene.frame_set(30)
    moved = bridge.read_mesh(body, depsgraph())
    assert np.array_equal(moved.vertices, rest.vertices)
    assert not np.allclose(moved.matrix_world, rest.matrix_world)
    assert np.allclose(moved.matrix_world, np.array(body.matrix_world))
    native.load().ColliderMesh(rest.vertices, rest.triangles)  # accepted as it is


def test_vertex_normals_are_blenders_without_its_last_bits(open_fixture):
    """hairdyn computes the head's vertex normals itself, from the vertices and triangles in
    a fixed order: Blender sums its own in parallel, and their last bits changed from run to
    run, and with them the simulation (Sintel's groom on its bust gave other bits in about one
    run in four). They are Blender's within 0.01 degree, and Blender's bits never enter them."""
    open_fixture("head_shake.blend")
    body = bpy.data.objects["Body"]
    mesh = bridge.read_mesh(body, depsgraph())
    blender = mesh.blender_normals.astype(np.float64)
    blender /= np.linalg.norm(blender, axis=1, keepdims=True)
    ours = mesh.normals()
    assert np.allclose(np.linalg.norm(ours, axis=1), 1.0, atol=1e-12)
    angles = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", ours, blender), -1.0, 1.0)))
    assert angles.max() < 0.01, angles.max()
    mesh.blender_normals[:] = np.float32(7.0)  # no vertex of the body is loose
    assert np.array_equal(mesh.normals(), ours)


def test_mesh_without_faces_is_a_clear_error(empty_scene):
    mesh = bpy.data.meshes.new("Loose")
    mesh.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [(0, 1)], [])
    obj = bpy.data.objects.new("Loose", mesh)
    empty_scene.collection.objects.link(obj)
    data = bridge.read_mesh(obj, depsgraph())
    with pytest.raises(ValueError, match="Invalid collider mesh: the mesh has no faces."):
        native.load().ColliderMesh(data.vertices, data.triangles)


def test_curves_round_trip_bit_exact(open_fixture):
    open_fixture("head_curves.blend")
    hair = bpy.data.objects["Hair"]
    groom = bridge.read_curves(hair, depsgraph())
    output = bridge.ensure_curves_output(None, "Out", groom.curve_offsets, like=hair)
    rng = np.random.default_rng(1)
    positions = rng.normal(size=groom.positions_wo.shape).astype(np.float32)
    bridge.write_curves(output, positions)
    back = np.empty_like(positions)
    output.data.position_data.foreach_get("vector", back.ravel())
    assert back.tobytes() == positions.tobytes()
    assert bridge.read_curves(output, depsgraph()).positions_wo.tobytes() == positions.tobytes()
    # The same object is reused while the topology matches.
    assert bridge.ensure_curves_output(output, "Out", groom.curve_offsets) == output
    assert output.data.materials[0] == hair.data.materials[0]
    assert "radius" in output.data.attributes


def test_write_back_is_visible_in_the_depsgraph(open_fixture):
    open_fixture("head_curves.blend")
    hair = bpy.data.objects["Hair"]
    groom = bridge.read_curves(hair, depsgraph())
    curves_out = bridge.ensure_curves_output(None, "Out", groom.curve_offsets)
    points_out = bridge.ensure_points_output(None, "OutPoints")
    shifted = groom.positions_wo + np.float32(0.5)
    direction = native.load().point_tangents(groom.curve_offsets, shifted)
    density = np.linspace(0.0, 1.0, len(shifted), dtype=np.float32)
    bridge.write_curves(curves_out, shifted)
    bridge.write_points(points_out, shifted, {"direction": direction, "density": density})

    graph = depsgraph()
    evaluated_curves = curves_out.evaluated_get(graph).data
    seen = np.empty_like(shifted)
    evaluated_curves.position_data.foreach_get("vector", seen.ravel())
    assert np.array_equal(seen, shifted)
    evaluated_mesh = points_out.evaluated_get(graph).data
    assert len(evaluated_mesh.vertices) == len(shifted) and len(evaluated_mesh.edges) == 0
    seen_points = np.empty_like(shifted)
    evaluated_mesh.vertices.foreach_get("co", seen_points.ravel())
    assert np.array_equal(seen_points, shifted)
    seen_density = np.empty_like(density)
    evaluated_mesh.attributes["density"].data.foreach_get("value", seen_density)
    assert np.array_equal(seen_density, density)
    seen_direction = np.empty_like(direction)
    evaluated_mesh.attributes["direction"].data.foreach_get("vector", seen_direction.ravel())
    assert np.array_equal(seen_direction, direction)
    assert np.allclose(np.linalg.norm(direction, axis=1), 1.0, atol=1e-6)


def test_written_positions_move_the_evaluated_bounds(open_fixture):
    """The outputs' bounds (which Blender culls, shadows and frames by) follow every frame's
    positions, not the first frame's: positions written through foreach_set alone leave the
    bounds Blender caches untouched (Blender 5.0: both outputs; 5.2 and 5.3: curves whose only
    write is the positions)."""
    open_fixture("head_curves.blend")
    hair = bpy.data.objects["Hair"]
    groom = bridge.read_curves(hair, depsgraph())
    curves_out = bridge.ensure_curves_output(None, "Out", groom.curve_offsets)
    points_out = bridge.ensure_points_output(None, "OutPoints")
    for shift in (0.0, 0.5, -0.25):
        positions = groom.positions_wo + np.float32(shift)
        bridge.write_curves(curves_out, positions)
        bridge.write_points(points_out, positions)
        graph = depsgraph()
        for output in (curves_out, points_out):
            corners = np.array([tuple(c) for c in output.evaluated_get(graph).bound_box])
            low, high = positions.min(axis=0), positions.max(axis=0)
            # Curves: the evaluated (smooth) curves pass through every written point.
            assert np.all(corners.min(axis=0) <= low + 1e-5), (output.type, shift)
            assert np.all(corners.max(axis=0) >= high - 1e-5), (output.type, shift)
            if output.type == 'MESH':
                assert np.allclose(corners.min(axis=0), low) and np.allclose(
                    corners.max(axis=0), high), shift


def _evaluated_points_node_group():
    """Geometry nodes: the curves' evaluated points (Catmull-Rom, at their resolution) as the
    vertices of a mesh, as a modifier downstream of the output would see them."""
    group, inputs, outputs = export.geometry_group("EvaluatedPoints")
    to_points = group.nodes.new("GeometryNodeCurveToPoints")
    to_points.mode = 'EVALUATED'
    to_vertices = group.nodes.new("GeometryNodePointsToVertices")
    group.links.new(inputs.outputs[0], to_points.inputs[0])
    group.links.new(to_points.outputs[0], to_vertices.inputs[0])
    group.links.new(to_vertices.outputs[0], outputs.inputs[0])
    return group


def test_written_positions_reach_the_evaluated_curves(open_fixture):
    """What Blender evaluates from the output curves (the smooth curves a geometry-nodes
    modifier or the viewport takes) follows every frame's positions: without the tag, Blender
    5.x kept evaluating the first frame's curves."""
    open_fixture("head_curves.blend")
    hair = bpy.data.objects["Hair"]
    groom = bridge.read_curves(hair, depsgraph())
    curves_out = bridge.ensure_curves_output(None, "Out", groom.curve_offsets)
    curves_out.modifiers.new("EvaluatedPoints", 'NODES').node_group = _evaluated_points_node_group()
    for shift in (0.0, 0.5):
        positions = groom.positions_wo + np.float32(shift)
        bridge.write_curves(curves_out, positions)
        graph = depsgraph()
        meshes = [
            instance.object.data
            for instance in graph.object_instances
            if instance.object.original == curves_out
            and isinstance(instance.object.data, bpy.types.Mesh)
        ]
        assert len(meshes) == 1 and len(meshes[0].vertices) >= len(positions)
        evaluated = np.empty(3 * len(meshes[0].vertices), np.float32)
        meshes[0].vertices.foreach_get("co", evaluated)
        evaluated = evaluated.reshape(-1, 3)
        # The evaluated curves pass through the written points and stay near them.
        assert np.allclose(evaluated.max(axis=0), positions.max(axis=0), atol=0.02), shift
        assert np.allclose(evaluated.min(axis=0), positions.min(axis=0), atol=0.02), shift


def test_arrays_cross_without_copies(open_fixture):
    open_fixture("head_curves.blend")
    hair = bpy.data.objects["Hair"]
    groom = bridge.read_curves(hair, depsgraph())
    _native = native.load()
    assert _native.buffer_address(groom.positions_wo) == groom.positions_wo.ctypes.data
    solver = _native.FollowSolver(groom.curve_offsets, groom.positions_wo, np.eye(4))
    view = solver.positions
    address = view.ctypes.data
    assert not view.flags.writeable and view.base is solver
    solver.step(1.0 / 24.0, np.diag([1.0, 1.0, 2.0, 1.0]))
    assert solver.positions.ctypes.data == address  # the same buffer, updated in place
    assert np.allclose(view[:, 2], groom.positions_wo[:, 2] * 2.0)


@pytest.mark.parametrize("dtype, shape, message", [
    (np.float64, (4, 3), "dtype float32"),
    (np.float32, (4, 2), r"shape \(N, 3\)"),
    (np.float32, (12,), r"shape \(N, 3\)"),
])
def test_bindings_reject_wrong_arrays(dtype, shape, message):
    _native = native.load()
    with pytest.raises(ValueError, match=message):
        _native.FollowSolver(np.array([0, 4], np.int32), np.zeros(shape, dtype), np.eye(4))


def test_bindings_reject_non_contiguous_and_lists():
    _native = native.load()
    strided = np.zeros((8, 3), np.float32)[::2]
    with pytest.raises(ValueError, match="C-contiguous"):
        _native.buffer_address(strided)
    with pytest.raises(ValueError, match="must be a numpy array, not list"):
        _native.buffer_address([[0.0, 0.0, 0.0]])


def make_hair(scene, sizes, name="BadHair"):
    curves = bridge.new_curves_data(name, sizes)
    obj = bpy.data.objects.new(name, curves)
    scene.collection.objects.link(obj)
    return obj


def test_empty_curves_object_is_a_clear_error(empty_scene):
    obj = bpy.data.objects.new("Empty", bpy.data.hair_curves.new("Empty"))
    empty_scene.collection.objects.link(obj)
    with pytest.raises(HairdynError, match="'Empty' has no hair strands"):
        bridge.read_groom(obj, depsgraph())


def test_single_point_strand_is_a_clear_error(empty_scene):
    head = bpy.data.objects.new("Head", bpy.data.meshes.new("Head"))
    empty_scene.collection.objects.link(head)
    obj = make_hair(empty_scene, [3, 1, 2])
    positions = np.arange(18, dtype=np.float32).reshape(6, 3) * np.float32(0.01)
    obj.data.position_data.foreach_set("vector", positions.ravel())
    obj.hairdyn.head = head
    with pytest.raises(HairdynError, match="strand 1 has 1 point.*at least 2"):
        simulation.Simulation(obj, depsgraph(), empty_scene)


def test_nan_positions_are_a_clear_error(empty_scene):
    head = bpy.data.objects.new("Head", bpy.data.meshes.new("Head"))
    empty_scene.collection.objects.link(head)
    obj = make_hair(empty_scene, [3, 3])
    positions = np.arange(18, dtype=np.float32).reshape(6, 3) * np.float32(0.01)
    positions[4, 1] = math.nan
    obj.data.position_data.foreach_set("vector", positions.ravel())
    obj.hairdyn.head = head
    with pytest.raises(HairdynError, match="not a finite number"):
        simulation.Simulation(obj, depsgraph(), empty_scene)


def test_hair_without_head_is_a_clear_error(empty_scene):
    obj = make_hair(empty_scene, [3])
    positions = np.arange(9, dtype=np.float32).reshape(3, 3)
    obj.data.position_data.foreach_set("vector", positions.ravel())
    with pytest.raises(HairdynError, match="has no head"):
        simulation.Simulation(obj, depsgraph(), empty_scene)


def test_not_hair_is_a_clear_error(open_fixture):
    open_fixture("head_curves.blend")
    with pytest.raises(HairdynError, match="'Camera' is not hair"):
        bridge.read_groom(bpy.data.objects["Camera"], depsgraph())


def test_zero_length_strands_are_dropped_with_a_count(empty_scene):
    head = bpy.data.objects.new("Head", bpy.data.meshes.new("Head"))
    empty_scene.collection.objects.link(head)
    obj = make_hair(empty_scene, [3, 3, 3])
    positions = np.array([[0, 0, 0], [0, 0, .1], [0, 0, .2],
                          [.1, 0, 0], [.1, 0, 0], [.1, 0, 0],  # three points on one spot
                          [.2, 0, 0], [.2, 0, .1], [.2, 0, .2]], np.float32)
    obj.data.position_data.foreach_set("vector", positions.ravel())
    obj.hairdyn.head = head
    obj.hairdyn.use_collision = False
    sim = simulation.Simulation(obj, depsgraph(), empty_scene)
    assert sim.groom.curves_num == 2 and sim.groom.points_num == 6
    assert np.array_equal(sim.groom.curve_offsets, [0, 3, 6])
    assert sim.groom.warnings == ["1 of the 3 strands of 'BadHair' have a zero-length segment "
                                  "(shorter than a millionth of the groom's size) and were "
                                  "left out"]
    obj.data.position_data.foreach_set("vector", np.zeros(27, np.float32))
    obj.data.update_tag()
    with pytest.raises(HairdynError, match="Every strand of 'BadHair' \\(3\\) has a zero-length"):
        bridge.read_groom(obj, depsgraph())


def test_head_without_vertices_is_a_clear_error(empty_scene):
    head = bpy.data.objects.new("Head", bpy.data.meshes.new("Head"))
    empty_scene.collection.objects.link(head)
    obj = make_hair(empty_scene, [3])
    obj.data.position_data.foreach_set("vector", np.float32([0, 0, 0, 0, 0, .1, 0, 0, .2]))
    obj.hairdyn.head = head
    obj.hairdyn.method = 'STRANDS'
    with pytest.raises(HairdynError, match="The mesh 'Head' has no vertices"):
        simulation.Simulation(obj, depsgraph(), empty_scene)


@pytest.mark.parametrize("count", [1, 2, 1537])
def test_set_rows_writes_the_objects_own_array_and_not_a_copys(empty_scene, count):
    """set_rows puts rows in bit for bit, into the object's own array: a copy that shares it
    (Blender 4 and later share arrays between copies until one is written) keeps its rows."""
    rng = np.random.default_rng(count)
    mesh = bpy.data.meshes.new("Rows")
    mesh.vertices.add(count)
    curves = bridge.new_curves_data("Rows", [count])
    for data in (mesh, curves):
        data.attributes.new("vector", 'FLOAT_VECTOR', 'POINT')
        data.attributes.new("scalar", 'FLOAT', 'POINT')

    def collections_of(mesh, curves):
        """(collection, field, width) of every array the test writes."""
        return [
            (mesh.attributes["vector"].data, "vector", 3),
            (mesh.attributes["scalar"].data, "value", 1),
            (mesh.vertices, "co", 3),
            (curves.attributes["vector"].data, "vector", 3),
            (curves.attributes["scalar"].data, "value", 1),
            (curves.position_data, "vector", 3),
        ]

    collections = collections_of(mesh, curves)

    def rows(width):
        return rng.normal(size=(count, width) if width > 1 else count).astype(np.float32)

    def read(collection, field, width):
        back = np.empty(count * width, dtype=np.float32)
        collection.foreach_get(field, back)
        return back

    before = [rows(width) for _, _, width in collections]
    for (collection, field, _), values in zip(collections, before):
        bridge.set_rows(collection, field, values)
    mesh_copy, curves_copy = mesh.copy(), curves.copy()
    after = [rows(width) for _, _, width in collections]
    for (collection, field, _), values in zip(collections, after):
        bridge.set_rows(collection, field, values)
    copies = collections_of(mesh_copy, curves_copy)
    for (collection, field, width), values in zip(collections, after):
        assert read(collection, field, width).tobytes() == values.tobytes(), field
    for (collection, field, width), values in zip(copies, before):
        assert read(collection, field, width).tobytes() == values.tobytes(), field


@pytest.mark.parametrize("count", [1, 700, 1024, 1537])
def test_points_output_positions_and_texture_space_are_blenders(empty_scene, count):
    """write_points puts the positions in bit for bit, whichever way the Blender stores them,
    and leaves the texture space Blender's automatic one would be (on meshes whose positions
    are vertices, hairdyn finds it natively; Blender's own search is slower there)."""
    rng = np.random.default_rng(count)
    positions = (rng.normal(size=(count, 3)) * [1.0, 1e-7, 0.0]).astype(np.float32)
    positions[:, 2] = 2.5  # a flat axis: Blender makes its size 1; the second one is tiny
    points = bridge.ensure_points_output(None, "Points")
    bridge.write_points(points, positions)
    bridge.write_points(points, positions)  # the second frame: the mesh kept
    reference = bpy.data.meshes.new("Reference")
    reference.vertices.add(count)
    reference.vertices.foreach_set("co", positions.ravel())
    reference.update()
    assert reference.use_auto_texspace
    for mesh in (points.data, points.evaluated_get(depsgraph()).data):
        back = np.empty_like(positions)
        mesh.vertices.foreach_get("co", back.ravel())
        assert back.tobytes() == positions.tobytes()
        assert tuple(mesh.texspace_location) == tuple(reference.texspace_location)
        assert tuple(mesh.texspace_size) == tuple(reference.texspace_size)


@pytest.mark.parametrize("close_tip", [False, True])
def test_particle_hairs_output_curves_take_its_material_and_the_radius_cycles_renders(
        open_fixture, close_tip):
    """Particle hair keeps its look in the output curves: the material of its system's slot,
    and per point the radius Cycles gives particle hair (radius_scale / 2 times the root and
    tip factors, blended by the shape: r = (1 - t)^(1 / (1 - shape)) (root - tip) + tip)."""
    from hairdyn import simulation

    open_fixture("head_particles.blend")
    body = bpy.data.objects["Body"]
    hair_material = bpy.data.materials.new("Hair")
    body.data.materials.append(hair_material)
    settings = body.particle_systems[0].settings
    settings.material = len(body.material_slots)
    settings.radius_scale, settings.root_radius, settings.tip_radius = 0.02, 1.5, 0.25
    settings.shape, settings.use_close_tip = 0.3, close_tip
    body.hairdyn.method = 'FOLLOW'
    simulation.run(bpy.context, body, 1, 1)
    curves = body.hairdyn.output_curves.data
    assert [m.name for m in curves.materials] == ["Hair"]
    radius = np.empty(len(curves.points), dtype=np.float32)
    curves.attributes["radius"].data.foreach_get("value", radius)
    sizes = np.diff(bridge._curve_offsets(curves))
    t = np.concatenate([np.linspace(0.0, 1.0, n) for n in sizes])
    expected = (1.0 - t) ** (1.0 / 0.7) * (0.015 - 0.0025) + 0.0025
    if close_tip:
        expected[np.cumsum(sizes) - 1] = 0.0
    assert np.allclose(radius, expected, rtol=1e-5, atol=1e-8)
    assert radius[0] == pytest.approx(0.015)
