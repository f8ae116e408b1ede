"""Owns: the swept-sphere extension of the Strands method (Ward & Lin 2003 §5): hair-hair
collision between strand segments as line-swept spheres on a grid (§5.3), and segment-exact
hair-object collision on a BVH of swept spheres (§5.4), hair-hair first, then the body (§5.5).
Native HairHairPass / SsvObjectPass do the work; its settings are SweptSphereParams.
"""

import numpy as np

from .base import Section
from .strands import Attached, Extension

BODY_MAPS, BODY_SWEPT, BODY_BOTH = 0, 1, 2  # SweptSphereParams.body_collision choices


class SweptSpheresAttached(Attached):
    def __init__(self, native, hair_hair, body, colliders, groom, thickness, radii):
        self.native, self.hair_hair, self.body = native, hair_hair, body
        self.colliders, self.groom, self.thickness = colliders, groom, thickness
        self.radii = radii
        self.ms, self.pairs, self.cutting, self.segments = [], [], 0.0, 0

    def after_step(self, solver, head_matrix):
        if self.hair_hair is not None:
            self.ms.append(solver.pass_ms("hair_hair"))
            self.pairs.append(self.hair_hair.stats["pairs_num"])
            self.hair_hair.reset_stats()
        if self.colliders is not None:
            share = self.native.segment_penetration_share(
                self.groom.curve_offsets,
                solver.positions,
                self.colliders.set,
                self.colliders.tolerance_wo(),
            )
            self.cutting += share
            self.segments += 1
        self.positions = solver.positions

    def report(self):
        figures = {}
        if self.hair_hair is not None:
            figures.update(
                hair_hair_ms=float(np.median(self.ms)) if self.ms else 0.0,
                hair_hair_pairs=int(np.median(self.pairs)) if self.pairs else 0,
                crossings=int(
                    self.native.count_crossings(
                        self.groom.curve_offsets, self.positions, self.radii, self.thickness
                    )
                ),
            )
        if self.colliders is not None:
            figures["segment_penetration_share"] = self.cutting / max(self.segments, 1)
        return figures


def attach(solver, build):
    params = build.params("swept_spheres")
    colliders = build.colliders
    use_body = colliders is not None and params.body_collision != BODY_MAPS
    if not params.hair_hair and not use_body:
        return None
    hair_hair = body = None
    radii = build.groom.radii  # the Curves radius attribute: each strand's own swept spheres
    if radii is not None:
        solver.set_radii(radii)
    if params.hair_hair:  # Ward & Lin 2003 §5.5: hair-hair first (soft)...
        hair_hair = build.native.HairHairPass(params)
        solver.add_pass(hair_hair)
    if use_body:  # ... then the body (hard)
        body = build.native.SsvObjectPass(colliders.set, params)
        solver.add_pass(body)
        if params.body_collision == BODY_SWEPT:
            solver.set_colliders(None, colliders.params)
    return SweptSpheresAttached(
        build.native, hair_hair, body, colliders, build.groom, params.thickness, radii
    )


EXTENSION = Extension(
    "swept_spheres",
    attach,
    params={"swept_spheres": "SweptSphereParams"},
    sections=(Section("Swept Spheres (Ward & Lin 2003)", "swept_spheres", rest=True),),
)
