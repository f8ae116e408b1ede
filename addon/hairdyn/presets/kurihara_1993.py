# hairdyn preset: the choices of Kurihara, Anjyo & Thalmann 1993 ("Hair Animation with
# Collision Detection"): angular strand dynamics integrated explicitly (eq. 7), cylindrical
# maps of 40 x 40 (§3.1), the reaction constraint with c = sqrt(2k) and no friction
# (eq. 12-15), child hairs around each simulated strand (§4 cluster model). The strand model is
# the paper's own: each hinge moves with its own segment's load and inertia (eq. 1-7), and the
# air's drag is eq. 6's linear term alone (no form drag).
import bpy
settings = bpy.context.object.hairdyn

settings.method = 'STRANDS'
settings.use_collision = True
settings.strands.model = 'KURIHARA1993'
settings.strands.form_drag = 0.0
settings.strands.integrator = 'EXPLICIT'
settings.strands.substeps = 8
settings.wind.speed = 0.0
settings.strands.children_per_guide = 10
settings.collision.map_kind = 'CYLINDER'
settings.collision.azimuth_num = 40
settings.collision.height_num = 40
settings.collision.damping = 0.0
settings.collision.friction = 0.0
