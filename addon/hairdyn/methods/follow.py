"""Owns: the Follow Head method, the kinematic baseline: every strand keeps its rest shape in
the head's frame (native FollowSolver). It reads only the collision report tolerance."""

from .base import Method


class Follow(Method):
    identifier = "FOLLOW"
    label = "Follow Head"
    description = (
        "Kinematic baseline: every strand keeps its rest shape in the head's frame "
        "and follows the head rigidly"
    )
    collision = ("report",)

    def __init__(self, build):
        self.solver = build.native.FollowSolver(
            build.groom.curve_offsets, build.groom.positions_wo, build.head_matrix
        )

    def step(self, frame_dt, head_matrix):
        self.solver.step(frame_dt, head_matrix)

    @property
    def positions(self):
        return self.solver.positions
