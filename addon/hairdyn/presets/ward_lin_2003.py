# hairdyn preset: the strand integration of Ward & Lin 2003 ("Adaptive Grouping and
# Subdivision for Simulating Hair Dynamics"): implicit backward Euler on the angular springs
# (appendix A), stable at one step per frame even with stiff hair.
import bpy
settings = bpy.context.object.hairdyn

settings.method = 'STRANDS'
settings.use_collision = True
settings.strands.integrator = 'IMPLICIT'
settings.strands.substeps = 1
settings.collision.map_kind = 'AUTO'
