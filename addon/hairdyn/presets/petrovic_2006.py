# hairdyn preset: the volumetric hair of Petrovic, Henne & Anderson 2006 ("Volumetric Methods
# for Simulation and Rendering of Hair"): the Strands method with hair-hair interaction as
# velocity smoothing on the density grid (§5.1, eq. 1; strength s = 0.2, a binomial filter of
# radius 1, the cell about a segment long) and the hair-shell normals (§4.1, eq. 2) written as
# shell_normal for the shell-normal material. Directing toward a target (§5.2) needs a target
# shape: pick it in the Volume section.
import bpy

settings = bpy.context.object.hairdyn

settings.method = 'STRANDS'
settings.volume_options.use_smoothing = True
settings.volume_options.use_shell_normals = True
settings.volume.smoothing = 0.2
settings.volume.filter_radius = 1
settings.volume.cell_size = 0.0
