"""Settings an artist edits, one PropertyGroup per object (Object.hairdyn).

Solver parameter groups mirror the native parameter structs field for field; a test checks
them against hairdyn._native's `fields()` tables so the panel and the solver cannot drift.
"""
import bpy
from bpy.props import (BoolProperty, CollectionProperty, EnumProperty, FloatProperty,
                       FloatVectorProperty, IntProperty, PointerProperty, StringProperty)

METHODS = (
    ("FOLLOW", "Follow Head",
     "Kinematic baseline: every strand keeps its rest shape in the head's frame and follows "
     "the head rigidly"),
    ("STRANDS", "Strands",
     "Strand dynamics: chains of rigid segments with hinge springs (Kurihara 1993), implicit "
     "integration (Ward & Lin 2003)"),
    ("LCP", "LCP",
     "Loosely connected particles (Bando 2003): particles sample the hair volume over the "
     "scalp, loose springs keep its length, SPH interactions its density; the strands follow "
     "the particles"),
)

# Properties shown in a unit scaled from the native struct's SI unit, so that hair-sized
# values read as ordinary numbers in the panel (Blender shows at most 6 decimals):
# property value = native value × scale.
DISPLAY_SCALES = {
    ("StrandParams", "k_theta"): 1e6,  # N·m/rad -> µN·m/rad
    ("StrandParams", "k_phi"): 1e6,
    ("StrandParams", "damping"): 1e9,  # N·m·s/rad -> nN·m·s/rad
    ("StrandParams", "line_density"): 1e6,  # kg/m -> mg/m
    ("StrandParams", "air_drag"): 1e6,  # N·s/m² -> µN·s/m²
}


def _is_mesh(_self, obj):
    return obj.type == 'MESH'


def native_params(group, params_class):
    """A native parameter struct (e.g. _native.CollisionParams) from its mirror PropertyGroup:
    field for field, enums by their position in the native `choices`, scaled fields back to
    SI (DISPLAY_SCALES)."""
    values = {}
    for field in params_class.fields():
        value = getattr(group, field["name"])
        if field["choices"]:
            value = field["choices"].split(",").index(value.lower())
        elif not isinstance(value, (bool, int, float)):
            value = tuple(value)
        scale = DISPLAY_SCALES.get((params_class.__name__, field["name"]))
        if scale is not None:
            value = value / scale
        values[field["name"]] = value
    return params_class(**values)


class HairdynStrandSettings(bpy.types.PropertyGroup):
    """Mirrors native StrandParams (native/strands/strand_params.hh) field for field."""

    k_theta: FloatProperty(
        name="Stiffness θ (k_θ)", default=0.1, min=0.0, max=1e6, soft_max=10.0, precision=4,
        description="k_θ, µN·m/rad: hinge spring toward the rest zenith angle (Kurihara 1993, "
                    "eq. 4), per segment")
    k_phi: FloatProperty(
        name="Stiffness φ (k_φ)", default=0.1, min=0.0, max=1e6, soft_max=10.0, precision=4,
        description="k_φ, µN·m/rad: hinge spring toward the rest azimuth (Kurihara 1993, "
                    "eq. 4), per segment")
    damping: FloatProperty(
        name="Damping (γ)", default=0.4, min=0.0, max=1e9, soft_max=100.0, precision=4,
        description="γ, nN·m·s/rad: damping of each segment's angular velocity (Kurihara 1993, "
                    "eq. 1)")
    line_density: FloatProperty(
        name="Line Density (c)", default=5.0, min=1e-3, max=1e6, soft_max=100.0, precision=3,
        description="c, mg/m: mass per length of a strand; sets the moment of inertia "
                    "(Kurihara 1993, eq. 2). A human hair is about 5 mg/m")
    gravity: FloatProperty(
        name="Gravity (g)", default=9.81, min=0.0, max=100.0, soft_max=30.0,
        description="g, m/s²: gravitational acceleration along world -Z (Kurihara 1993, eq. 6)")
    wind_speed: FloatProperty(
        name="Wind Speed (|f|)", default=0.0, min=0.0, max=100.0, soft_max=20.0,
        description="|f|, m/s: speed of the wind (Kurihara 1993, eq. 6)")
    wind_direction: FloatVectorProperty(
        name="Wind Direction", size=3, default=(0.0, 1.0, 0.0), min=-1.0, max=1.0,
        subtype='DIRECTION',
        description="World direction the wind blows toward (normalised; zero means no wind)")
    wind_noise: FloatProperty(
        name="Turbulence", default=0.3, min=0.0, max=10.0, soft_max=2.0,
        description="Relative amount of smooth turbulence added to the wind")
    wind_noise_frequency: FloatProperty(
        name="Turbulence Frequency", default=0.5, min=0.0, max=100.0, soft_max=5.0,
        description="Hz: frequency of the wind's turbulence")
    air_drag: FloatProperty(
        name="Air Drag (c_air)", default=50.0, min=0.0, max=1e6, soft_max=1000.0,
        description="c_air, µN·s/m²: air drag per length and relative speed; carries the wind "
                    "and damps motion through the air (Kurihara 1993, eq. 6)")
    integrator: EnumProperty(
        name="Integrator", default='IMPLICIT',
        items=(('EXPLICIT', "Explicit", "Kurihara 1993, eq. 7: fast, needs small steps with "
                                        "stiff hair"),
               ('IMPLICIT', "Implicit", "Backward Euler, Ward & Lin 2003 appendix A: stable "
                                        "at any stiffness")),
        description="How the hinge equations are integrated")
    substeps: IntProperty(
        name="Substeps", default=4, min=1, max=1000, soft_max=32,
        description="Solver steps per frame; the head's motion is interpolated over them")
    children_per_guide: IntProperty(
        name="Children per Guide", default=10, min=0, max=1000, soft_max=100,
        description="Render hairs generated around each simulated guide (Kurihara 1993, §4)")
    child_mode: EnumProperty(
        name="Children", default='CLUSTER',
        items=(('CLUSTER', "Clusters", "Around each guide, within the spread of its root "
                                       "(Kurihara 1993, §4)"),
               ('INTERPOLATE', "Interpolated", "Spread over the scalp between the guides, each "
                                               "blending its nearest guides")),
        description="Where the child hairs take root")
    child_spread: FloatProperty(
        name="Child Spread", default=0.01, min=0.0, max=1.0, soft_max=0.05, subtype='DISTANCE',
        precision=4,
        description="m: radius around a guide's root within which its children take root")
    seed: IntProperty(
        name="Seed", default=0, min=0, max=2147483647,
        description="Seed of the wind turbulence and of the child roots")


class HairdynLcpSettings(bpy.types.PropertyGroup):
    """Mirrors native LcpParams (native/lcp/lcp_params.hh) field for field."""

    particle_spacing: FloatProperty(
        name='Particle Spacing (r)', default=0.012, min=0.0001, max=1.0, precision=4, subtype='DISTANCE',
        description='r, m: Poisson-disc radius of the particles in the (u, v, s) distance of eq. 3')
    particle_num: IntProperty(
        name='Particle Count (N)', default=2000, min=0, max=10000000,
        description='N: Target particle count (0: as many as the spacing allows)')
    root_depth: FloatProperty(
        name='Root Depth (s_r)', default=0.01, min=0.0, max=1.0, precision=4, subtype='DISTANCE',
        description='s_r, m: Depth of the fixed root particles beneath the scalp (§3.2)')
    max_length: FloatProperty(
        name='Max Length (L_max)', default=0.25, min=0.0001, max=10.0, precision=4, subtype='DISTANCE',
        description='L_max, m: Hair length where the length map is 1 (§3.2)')
    root_tangent_weight: FloatProperty(
        name='Root Tangent Weight (w_t)', default=0.3, min=0.0, max=100.0, precision=4,
        description='w_t: Tangent weight of the root direction, eq. 4 (large: hair lies down)')
    root_normal_weight: FloatProperty(
        name='Root Normal Weight (w_n)', default=1.0, min=0.0, max=100.0, precision=4,
        description='w_n: Normal weight of the root direction, eq. 4')
    whorl_u: FloatProperty(
        name='Whorl U (u_w)', default=0.5, min=0.0, max=1.0, precision=4,
        description='u_w: u of the hair whorl centre on the scalp (eq. 4)')
    whorl_v: FloatProperty(
        name='Whorl V (v_w)', default=0.5, min=0.0, max=1.0, precision=4,
        description='v_w: v of the hair whorl centre on the scalp (eq. 4)')
    beam_length: FloatProperty(
        name='Beam Length (b)', default=0.03, min=0.001, max=100.0, precision=4, subtype='DISTANCE',
        description='b, m: Bending length (EI/λg)^(1/3) of the cantilever-beam initial shape (Anjyo 1992)')
    seed: IntProperty(
        name='Seed', default=0, min=0, max=2147483647,
        description='Random seed of the Poisson-disc sampling')
    h1: FloatProperty(
        name='Connection Radius (h₁)', default=0.016, min=1e-05, max=1.0, precision=4, subtype='DISTANCE',
        description='h₁, m: Smoothing length of the connections: pairs within 2h₁ at rest (eq. 7)')
    a0: FloatProperty(
        name='Alignment Threshold (a₀)', default=0.5, min=0.0, max=1.0, precision=4,
        description='a₀: Alignment threshold: pairs with a_ij < a₀ are dropped (eq. 6)')
    neighbor_num: IntProperty(
        name='Connections per Particle (N_n)', default=12, min=1, max=1000,
        description='N_n: Connections kept per particle, strongest c_ij W(l_ij, h₁) first (§3.2)')
    young_modulus: FloatProperty(
        name="Young's Modulus (E)", default=10000.0, min=0.0, max=1000000000.0, precision=1,
        description="E, Pa: Tensile Young's modulus kept constant per particle (eq. 10-14)")
    material_density: FloatProperty(
        name='Material Density (δ)', default=1300.0, min=1.0, max=100000.0, precision=4,
        description='δ, kg/m³: Density of the hair material, giving the cross-section A_i (eq. 9)')
    spring_damping: FloatProperty(
        name='Spring Damping (γ)', default=0.005, min=0.0, max=10.0, precision=4,
        description='γ, s: Damping of the springs: force γ·α_ij k_ij·(v_ij·x̂_ij) (§3.3)')
    implicit_springs: BoolProperty(
        name='Implicit Springs', default=True,
        description='Integrate the springs implicitly (backward Euler): few substeps at any '
                    'stiffness. Off: explicit springs, substeps added as their stiffness needs')
    hair_density: FloatProperty(
        name='Hair Density (ρ_h)', default=10.0, min=0.001, max=10000.0, precision=4,
        description='ρ_h, kg/m³: Mass of hair per volume of the hair region; sets the particle mass m_i')
    h2: FloatProperty(
        name='Interaction Radius (h₂)', default=0.011, min=1e-05, max=1.0, precision=4, subtype='DISTANCE',
        description='h₂, m: Smoothing length of hair-hair interactions (eq. 1, 16-18)')
    attraction_repulsion: BoolProperty(
        name='Attraction and Repulsion', default=True,
        description='Apply attraction/repulsion (eq. 16)')
    pressure_stiffness: FloatProperty(
        name='Attraction Strength (k_a)', default=0.2, min=0.0, max=10000.0, precision=4,
        description='k_a, m²/s²: Magnitude of the attraction/repulsion, P = k_a(ρ − ρ₀) (eq. 16)')
    rest_density: FloatProperty(
        name='Rest Density (ρ₀)', default=8.0, min=0.0, max=100000.0, precision=4,
        description='ρ₀, kg/m³: Average hair density kept by eq. 16: small is repulsive, large cohesive')
    hair_collision: BoolProperty(
        name='Hair Collision', default=True,
        description='Apply inelastic hair-hair collision (eq. 17)')
    collision_damping: FloatProperty(
        name='Collision Damping (d_c)', default=60.0, min=0.0, max=1000000.0, precision=4,
        description='d_c, 1/s: Collision damping constant of eq. 17 (per unit SPH volume)')
    hair_friction: BoolProperty(
        name='Hair Friction', default=True,
        description='Apply hair-hair friction (eq. 18)')
    friction_damping: FloatProperty(
        name='Friction Damping (d_f)', default=10.0, min=0.0, max=1000000.0, precision=4,
        description='d_f, 1/s: Frictional damping constant of eq. 18 (per unit SPH volume)')
    gravity: FloatVectorProperty(
        name='Gravity (g)', size=3, default=(0.0, 0.0, -9.81), min=-1000.0, max=1000.0,
        subtype='ACCELERATION', description='g, m/s²: Acceleration of gravity, world space (§3.5)')
    air_friction: FloatProperty(
        name='Air Friction', default=2.0, min=0.0, max=10000.0, precision=4,
        description='1/s: Air friction: damping force proportional to velocity (§3.5)')
    wind_particle_spacing: FloatProperty(
        name='Wind Particle Spacing', default=0.03, min=0.001, max=1.0, precision=4, subtype='DISTANCE',
        description='m: Spacing (and smoothing length) of the air particles')
    wind_drag: FloatProperty(
        name='Wind Drag (k_d)', default=20.0, min=0.0, max=100000.0, precision=4,
        description='k_d, 1/s: Drag between hair and air particles, acting on both (§3.5)')
    air_density: FloatProperty(
        name='Air Density', default=1.2, min=0.001, max=1000.0, precision=4,
        description='kg/m³: Density of the air particles')
    body_friction: FloatProperty(
        name='Body Friction (μ)', default=0.3, min=0.0, max=10.0, precision=4,
        description='μ: Coulomb friction coefficient of hair sliding on the body (§3.5)')
    substeps: IntProperty(
        name='Substeps', default=1, min=1, max=1000,
        description='Fewest time steps per frame; more are taken as the hair-hair pressure '
                    '(eq. 16) or explicit springs need')
    max_substeps: IntProperty(
        name='Max Substeps', default=200, min=1, max=100000,
        description='Most time steps per frame: a frame whose stability bounds (hair-hair '
                    'pressure CFL, explicit springs) need more is refused with the reason')


class HairdynCollisionSettings(bpy.types.PropertyGroup):
    """Mirrors native CollisionParams (native/collision/collision_params.hh) field for field."""

    azimuth_num: IntProperty(
        name="Map Columns (m)", default=40, min=4, max=4096,
        description="m: azimuth samples of each collision map (Kurihara 1993, eq. 8; the "
                    "paper uses 40)")
    height_num: IntProperty(
        name="Map Rows (n)", default=40, min=4, max=4096,
        description="n: height (cylinder) or polar (sphere) samples of each collision map "
                    "(Kurihara 1993, eq. 8; the paper uses 40)")
    map_kind: EnumProperty(
        name="Map", default='AUTO',
        items=(('AUTO', "Automatic", "Per part, the map with the smaller error against the mesh"),
               ('CYLINDER', "Cylinder", "Cylindrical map (r, θ, y), Kurihara 1993 §3.1"),
               ('SPHERE', "Sphere", "Spherical map (r, θ, φ), Kurihara 1993 §5")),
        description="Map per collider part")
    axis_mode: EnumProperty(
        name="Axis", default='FITTED',
        items=(('FITTED', "Fitted", "Principal axis of the part's surface"),
               ('OBJECT_X', "Object X", "The collider's local X axis through the part's centre"),
               ('OBJECT_Y', "Object Y", "The collider's local Y axis through the part's centre"),
               ('OBJECT_Z', "Object Z", "The collider's local Z axis through the part's centre")),
        description="Where each part's map axis comes from")
    stiffness: FloatProperty(
        name="Stiffness (k)", default=1.0e4, min=0.0, max=1.0e9, soft_max=1.0e6,
        description="k, 1/s²: strength of the reaction constraint pulling a node to the surface "
                    "(Kurihara 1993, eq. 13)")
    damping: FloatProperty(
        name="Damping (c)", default=0.0, min=0.0, max=1.0e6, soft_max=1000.0,
        description="c, 1/s: damping of the normal velocity in the reaction constraint; 0 uses "
                    "the paper's c = √(2k) (Kurihara 1993, eq. 13)")
    friction: FloatProperty(
        name="Friction (μ)", default=0.0, min=0.0, max=10.0, soft_max=2.0,
        description="μ: Coulomb friction against colliders; 0 reproduces Kurihara 1993 (an "
                    "extension of eq. 14)")
    projection_tolerance: FloatProperty(
        name="Projection Tolerance", default=0.001, min=0.0, max=1.0, precision=4,
        description="Nodes deeper than this share of the collider's size (bounding-box "
                    "diagonal) are put back on the surface (Ward & Lin 2003 §5.5)")
    penetration_tolerance: FloatProperty(
        name="Report Tolerance", default=0.01, min=0.0, max=1.0, precision=4,
        description="Depth, as a share of the collider's size (bounding-box diagonal), counted "
                    "as penetration in the quality report")


class HairdynColliderItem(bpy.types.PropertyGroup):
    object: PointerProperty(name="Collider", type=bpy.types.Object, poll=_is_mesh,
                            description="A mesh the hair collides with")


class HairdynSettings(bpy.types.PropertyGroup):
    enabled: BoolProperty(
        name="hairdyn", default=False,
        description="Simulate this hair with hairdyn: play back its bake, or simulate it live, "
                    "whenever the frame changes")
    method: EnumProperty(
        name="Method", items=METHODS, default="FOLLOW",
        description="How the hair moves")
    head: PointerProperty(
        name="Head", type=bpy.types.Object, poll=_is_mesh,
        description="Mesh the hair roots are attached to. Empty: the Curves object's surface, "
                    "or the mesh that emits the particle hair")
    strands: PointerProperty(type=HairdynStrandSettings, name="Strand Settings")
    lcp: PointerProperty(type=HairdynLcpSettings, name="LCP Settings")
    use_billboards: BoolProperty(
        name="Billboards", default=True,
        description="Show LCP particles as hair-textured cards along the hair direction, "
                    "faded by 1/sin θ (Bando 2003 §4), in the viewport and in Cycles")
    lcp_init: EnumProperty(
        name="Particles From", default='SCALP',
        items=(('SCALP', "Scalp",
                "Poisson-disc samples of the hair volume over the scalp's (u, v) and the arc "
                "length s up to the length map, in a cantilever-beam shape (Bando 2003 §3.2)"),
               ('GROOM', "Groom",
                "Samples along the groom's strands: u, v from the root's surface position, s "
                "from arc length, directions from the tangents (Bando 2003 §3.2); needs no "
                "scalp")),
        description="Where LCP's particles start (Bando 2003 §3.2)")
    lcp_scalp_source: EnumProperty(
        name="Scalp From", default='GROUP',
        items=(('GROUP', "Vertex Group",
                "The head's faces whose corners all lie in a vertex group (Bando 2003 §3.2)"),
               ('FACES', "Selected Faces",
                "The head mesh's selected faces (Bando 2003 §3.2)")),
        description="How the part of the head that grows hair is marked (Bando 2003 §3.2)")
    lcp_scalp: StringProperty(
        name="Scalp", default="scalp",
        description="Vertex group of the head that marks the scalp LCP samples the hair volume "
                    "over (Bando 2003 §3.2)")
    lcp_length_source: EnumProperty(
        name="Lengths From", default='GROOM',
        items=(('GROOM', "Groom",
                "At each scalp point the length of the groom's nearest strand; the longest "
                "strand is L_max (Bando 2003 §3.2)"),
               ('IMAGE', "Image",
                "A grey image over the scalp's (u, v), scaled by Max Length L_max (Bando 2003 "
                "§3.2)"),
               ('WEIGHTS', "Vertex Weights",
                "A vertex group of the head, its weights scaled by Max Length L_max (Bando "
                "2003 §3.2)")),
        description="The length map L(u, v): how long the hair grows over the scalp (Bando "
                    "2003 §3.2)")
    lcp_length_image: PointerProperty(
        name="Length Image", type=bpy.types.Image,
        description="Grey image of the length map L(u, v) / L_max over the scalp's harmonic "
                    "(u, v) (Bando 2003 §3.2): columns from u = 0, rows from v = 0 at the "
                    "bottom; white grows hair of Max Length, black none")
    lcp_length_group: StringProperty(
        name="Length Group", default="length",
        description="Vertex group of the head whose weights are the length map L / L_max "
                    "(Bando 2003 §3.2): weight 1 grows hair of Max Length, 0 none")
    output_children: PointerProperty(
        name="Output Children", type=bpy.types.Object,
        description="Curves object that receives the child hairs every frame (created when "
                    "empty)")
    use_collision: BoolProperty(
        name="Collision", default=True,
        description="Collide the hair with the head and the other colliders (cylindrical and "
                    "spherical maps, Kurihara 1993 §3)")
    use_default_colliders: BoolProperty(
        name="Default Colliders", default=True,
        description="Collide with the head, and with every mesh that has Blender's Collision "
                    "modifier")
    colliders: CollectionProperty(type=HairdynColliderItem, name="Colliders",
                                  description="More meshes the hair collides with")
    collider_index: IntProperty(name="Active Collider", default=0, min=0)
    collider_parts: StringProperty(
        name="Parts", default="head,neck,torso,arms,arm.L,arm.R",
        description="Vertex groups that get a map of their own (comma separated): head, neck, "
                    "torso... A collider with none of them is one part")
    collision: PointerProperty(type=HairdynCollisionSettings, name="Collision Settings")
    frame_start: IntProperty(
        name="Start", default=1, min=-1048574, max=1048574,
        description="First frame of the simulation: the groom's rest shape is read here")
    frame_end: IntProperty(
        name="End", default=250, min=-1048574, max=1048574,
        description="Last frame of the simulation")
    output_curves: PointerProperty(
        name="Output Curves", type=bpy.types.Object,
        description="Curves object that receives the simulated strands every frame "
                    "(created when empty)")
    output_points: PointerProperty(
        name="Output Points", type=bpy.types.Object,
        description="Mesh of loose vertices that receives the simulated points and their "
                    "attributes every frame (created when empty)")
    cache_directory: StringProperty(
        name="Cache", subtype='DIR_PATH', default="//hairdyn_cache/",
        description="Folder the bake writes to; // is relative to the .blend file. Each hair "
                    "object bakes into a subfolder named after it")
    use_cache: BoolProperty(
        name="Play Back Bake", default=True,
        description="Load the baked frame into the output objects whenever the frame changes")
    use_live: BoolProperty(
        name="Simulate on Playback", default=True,
        description="Where no frame is baked, simulate while the animation plays: restart at "
                    "the start frame, step when the frame advances by one (like cloth)")


def settings_dict(settings):
    """The solver parameters of a settings group as plain values (for a cache manifest):
    every property but object pointers and the cache's own settings; images by name."""
    skip = {"rna_type", "name", "enabled", "head", "collider_index", "output_children",
            "use_billboards", "output_curves", "output_points", "cache_directory",
            "use_cache", "use_live"}
    result = {}
    for prop in settings.bl_rna.properties:
        if prop.identifier in skip:
            continue
        value = getattr(settings, prop.identifier)
        if prop.type == 'POINTER':
            if isinstance(value, bpy.types.PropertyGroup):
                result[prop.identifier] = settings_dict(value)
            elif prop.fixed_type.identifier == 'Image':  # the length map: by name
                result[prop.identifier] = value.name if value is not None else None
        elif prop.type == 'COLLECTION':
            result[prop.identifier] = [item.object.name for item in value if item.object]
        elif hasattr(value, "__len__") and not isinstance(value, str):
            result[prop.identifier] = list(value)
        else:
            result[prop.identifier] = value
    return result
