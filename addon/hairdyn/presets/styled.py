# hairdyn preset: a styled cut that holds its shape (gel, a short spiky cut, a mohawk). The
# articulated strand model with gel-bound strands: the gel glues hairs into clumps that bend
# like one thicker strand (radius 100 um: Gamma = c g L^3 / EI about 1.2 for a 12 cm strand,
# against 16 for loose human hair), stiffened further toward the root (20x, fading over 60% of
# the length), and damped so a shake settles quickly. Gravity still acts: long hair under
# this preset still droops, as gelled long hair does.
# cpp_tests/test_strands_articulated.cpp (StyledPresetHoldsASpikyCrown) reads this file.
import bpy

settings = bpy.context.object.hairdyn

settings.method = 'STRANDS'
settings.strands.model = 'ARTICULATED'
settings.strands.integrator = 'IMPLICIT'
settings.strands.youngs_modulus = 3.5  # GPa (the panel's unit)
settings.strands.strand_radius = 100.0  # µm
settings.strands.hair_density = 1300.0
settings.strands.root_stiffness = 20.0
settings.strands.root_length = 0.6
settings.strands.bending_damping = 10.0  # ms
settings.strands.substeps = 2
