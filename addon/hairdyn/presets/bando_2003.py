# hairdyn preset: the choices of Bando, Chen & Nishita 2003 ("Animating Hair with Loosely
# Connected Particles"): particles over the scalp, pairs with a_ij >= a0 = 0.5 pruned to about
# N_n = 12 per particle (§3.2), constant tensile modulus (eq. 10-14), SPH hair-hair
# attraction/repulsion, collision and friction (eq. 16-18), body collision with friction.
import bpy
settings = bpy.context.object.hairdyn

settings.method = 'LCP'
settings.use_collision = True
settings.lcp.a0 = 0.5
settings.lcp.neighbor_num = 12
settings.lcp.attraction_repulsion = True
settings.lcp.hair_collision = True
settings.lcp.hair_friction = True
settings.wind.speed = 0.0
