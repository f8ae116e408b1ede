"""Billboards for LCP particles (Bando 2003 §4): a geometry-nodes setup that instances a
textured card on every particle, its long axis along the hair direction t, its width parallel
to the screen, its opacity scaled by 1 / sin θ (cos θ = t · d, d toward the camera), its size
set by a width and an aspect. Cycles and the viewport show the instances.

The node group and the material are built once per file and shared; the modifier sits on the
particle output object. Node API differences between Blender versions are detected, not
guessed from version numbers.
"""

import math

import bpy

GROUP_NAME = "hairdyn Billboards"
MATERIAL_NAME = "hairdyn Billboard"
MODIFIER_NAME = "hairdyn Billboards"
OPACITY = "hairdyn_opacity"  # per-instance attribute the material reads
INPUTS = (
    ("Geometry", 'NodeSocketGeometry'),
    ("Camera", 'NodeSocketObject'),
    ("Card Width", 'NodeSocketFloat'),
    ("Card Aspect", 'NodeSocketFloat'),
    ("Opacity", 'NodeSocketFloat'),
)


def _socket(sockets, name):
    """The enabled socket called `name` (older Blender keeps one hidden socket per type)."""
    return next(s for s in sockets if s.name == name and s.enabled)


def _add_interface(tree):
    if hasattr(tree, "interface"):  # Blender 4.0+
        for name, kind in INPUTS:
            tree.interface.new_socket(name, in_out='INPUT', socket_type=kind)
        tree.interface.new_socket("Geometry", in_out='OUTPUT', socket_type='NodeSocketGeometry')
    else:
        for name, kind in INPUTS:
            tree.inputs.new(kind, name)
        tree.outputs.new('NodeSocketGeometry', "Geometry")


def input_identifiers(tree):
    """{input name: the identifier a modifier stores its value under}."""
    if hasattr(tree, "interface"):
        return {
            item.name: item.identifier
            for item in tree.interface.items_tree
            if item.item_type == 'SOCKET' and item.in_out == 'INPUT'
        }
    return {socket.name: socket.identifier for socket in tree.inputs}


def _vector_math(nodes, links, operation, a, b=None):
    node = nodes.new("ShaderNodeVectorMath")
    node.operation = operation
    links.new(a, node.inputs[0])
    if b is not None:
        links.new(b, node.inputs[1])
    return node


def _math(nodes, links, operation, a, b):
    node = nodes.new("ShaderNodeMath")
    node.operation = operation
    for index, value in enumerate((a, b)):
        if isinstance(value, float):
            node.inputs[index].default_value = value
        else:
            links.new(value, node.inputs[index])
    return node.outputs[0]


def build_group(material):
    """The node group: particles in, oriented and faded cards out."""
    tree = bpy.data.node_groups.new(GROUP_NAME, 'GeometryNodeTree')
    _add_interface(tree)
    nodes, links = tree.nodes, tree.links
    group_in = nodes.new("NodeGroupInput")
    group_out = nodes.new("NodeGroupOutput")

    # The card: a quad of 1 x aspect in the XZ plane (width along X, hair along Z).
    card = nodes.new("GeometryNodeMeshGrid")
    card.inputs["Vertices X"].default_value = 2
    card.inputs["Vertices Y"].default_value = 2
    card.inputs["Size X"].default_value = 1.0
    links.new(group_in.outputs["Card Aspect"], card.inputs["Size Y"])
    stand_up = nodes.new("GeometryNodeTransform")
    stand_up.inputs["Rotation"].default_value = (math.pi / 2, 0.0, 0.0)
    links.new(card.outputs["Mesh"], stand_up.inputs["Geometry"])
    set_material = nodes.new("GeometryNodeSetMaterial")
    set_material.inputs["Material"].default_value = material
    links.new(stand_up.outputs["Geometry"], set_material.inputs["Geometry"])

    # t from the particles, d toward the camera, the card's width h = t x d (on screen).
    direction = nodes.new("GeometryNodeInputNamedAttribute")
    direction.data_type = 'FLOAT_VECTOR'
    direction.inputs["Name"].default_value = "direction"
    t = _socket(direction.outputs, "Attribute")
    camera = nodes.new("GeometryNodeObjectInfo")
    links.new(group_in.outputs["Camera"], camera.inputs["Object"])
    position = nodes.new("GeometryNodeInputPosition")
    to_camera = _vector_math(
        nodes, links, 'SUBTRACT', camera.outputs["Location"], position.outputs["Position"]
    )
    d = _vector_math(nodes, links, 'NORMALIZE', to_camera.outputs["Vector"])
    across = _vector_math(nodes, links, 'CROSS_PRODUCT', t, d.outputs["Vector"])
    h = _vector_math(nodes, links, 'NORMALIZE', across.outputs["Vector"])

    # Rotation: the card's Z along t, then its X along h about Z.
    along = nodes.new("FunctionNodeAlignEulerToVector")
    along.axis = 'Z'
    links.new(t, along.inputs["Vector"])
    facing = nodes.new("FunctionNodeAlignEulerToVector")
    facing.axis = 'X'
    facing.pivot_axis = 'Z'
    links.new(along.outputs["Rotation"], facing.inputs["Rotation"])
    links.new(h.outputs["Vector"], facing.inputs["Vector"])

    # Opacity / sin θ, sin θ = |t x d|, at most 1 (Bando 2003 §4).
    sin_theta = _vector_math(nodes, links, 'LENGTH', across.outputs["Vector"])
    scaled = _math(
        nodes,
        links,
        'DIVIDE',
        group_in.outputs["Opacity"],
        _math(nodes, links, 'MAXIMUM', sin_theta.outputs["Value"], 1e-3),
    )
    opacity = _math(nodes, links, 'MINIMUM', scaled, 1.0)
    store = nodes.new("GeometryNodeStoreNamedAttribute")
    store.data_type = 'FLOAT'
    store.domain = 'POINT'
    store.inputs["Name"].default_value = OPACITY
    links.new(group_in.outputs["Geometry"], store.inputs["Geometry"])
    links.new(opacity, _socket(store.inputs, "Value"))

    instance = nodes.new("GeometryNodeInstanceOnPoints")
    links.new(store.outputs["Geometry"], instance.inputs["Points"])
    links.new(set_material.outputs["Geometry"], instance.inputs["Instance"])
    links.new(facing.outputs["Rotation"], instance.inputs["Rotation"])
    links.new(group_in.outputs["Card Width"], instance.inputs["Scale"])
    links.new(instance.outputs["Instances"], group_out.inputs["Geometry"])
    return tree


def build_material():
    """A hair-textured card: strands along the card as bands, faded by the opacity."""
    material = bpy.data.materials.new(MATERIAL_NAME)
    if material.node_tree is None:  # newer Blender gives every material its node tree
        material.use_nodes = True
    if hasattr(material, "blend_method"):  # EEVEE Legacy's transparency setting
        material.blend_method = 'HASHED'
    nodes, links = material.node_tree.nodes, material.node_tree.links
    principled = nodes["Principled BSDF"]
    principled.inputs["Base Color"].default_value = (0.35, 0.2, 0.1, 1.0)
    coordinates = nodes.new("ShaderNodeTexCoord")
    bands = nodes.new("ShaderNodeTexWave")
    bands.wave_type = 'BANDS'
    bands.bands_direction = 'X'  # stripes across the width: strands along the card
    bands.inputs["Scale"].default_value = 6.0
    bands.inputs["Distortion"].default_value = 4.0
    links.new(coordinates.outputs["Object"], bands.inputs["Vector"])
    opacity = nodes.new("ShaderNodeAttribute")
    opacity.attribute_type = 'INSTANCER'
    opacity.attribute_name = OPACITY
    alpha = nodes.new("ShaderNodeMath")
    alpha.operation = 'MULTIPLY'
    links.new(bands.outputs["Fac"], alpha.inputs[0])
    links.new(opacity.outputs["Fac"], alpha.inputs[1])
    transparent = nodes.new("ShaderNodeBsdfTransparent")
    mix = nodes.new("ShaderNodeMixShader")
    links.new(alpha.outputs[0], mix.inputs["Fac"])
    links.new(transparent.outputs[0], mix.inputs[1])
    links.new(principled.outputs[0], mix.inputs[2])
    links.new(mix.outputs[0], nodes["Material Output"].inputs["Surface"])
    return material


def _modifier_inputs(modifier):
    """Blender 5.2+ shows a Geometry Nodes modifier's inputs as RNA structs
    (modifier.properties.inputs.<identifier>.value); earlier ones as ID properties."""
    return getattr(getattr(modifier, "properties", None), "inputs", None)


def set_input(modifier, identifier, value):
    inputs = _modifier_inputs(modifier)
    if inputs is None:
        modifier[identifier] = value
    else:
        getattr(inputs, identifier).value = value


def get_input(modifier, identifier):
    inputs = _modifier_inputs(modifier)
    return modifier.get(identifier) if inputs is None else getattr(inputs, identifier).value


def ensure(points_obj, camera, card_width=0.02, card_aspect=3.0, opacity=0.5):
    """The billboard modifier on the particle output object (node group and material made
    once per file). `camera` orients the cards; None leaves them facing +Y."""
    material = bpy.data.materials.get(MATERIAL_NAME) or build_material()
    tree = bpy.data.node_groups.get(GROUP_NAME) or build_group(material)
    modifier = points_obj.modifiers.get(MODIFIER_NAME)
    if modifier is None:
        modifier = points_obj.modifiers.new(MODIFIER_NAME, 'NODES')
        modifier.node_group = tree
        ids = input_identifiers(tree)
        set_input(modifier, ids["Card Width"], card_width)
        set_input(modifier, ids["Card Aspect"], card_aspect)
        set_input(modifier, ids["Opacity"], opacity)
    camera_id = input_identifiers(tree)["Camera"]
    if camera is not None and get_input(modifier, camera_id) != camera:
        set_input(modifier, camera_id, camera)
    if material.name not in points_obj.data.materials:
        points_obj.data.materials.append(material)
    return modifier
