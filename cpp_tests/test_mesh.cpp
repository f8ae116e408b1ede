#include <gtest/gtest.h>

#include "collision/mesh.hh"

using namespace hairdyn;

namespace {

/* A closed tetrahedron. */
const std::vector<vec3> tet_vertices{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
const std::vector<ivec3> tet_triangles{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

}  // namespace

TEST(Mesh, ClosedTetrahedron)
{
  ASSERT_EQ(find_mesh_error(tet_vertices, tet_triangles), "");
  const ColliderMesh mesh(tet_vertices, tet_triangles);
  EXPECT_EQ(mesh.vertices_num(), 4);
  EXPECT_EQ(mesh.triangles_num(), 4);
  EXPECT_EQ(mesh.skipped_triangles_num(), 0);
  EXPECT_EQ(mesh.boundary_edges_num(), 0);
}

TEST(Mesh, OpenMeshHasBoundary)
{
  const std::vector<ivec3> open(tet_triangles.begin(), tet_triangles.begin() + 3);
  const ColliderMesh mesh(tet_vertices, open);
  EXPECT_EQ(mesh.boundary_edges_num(), 3);
}

TEST(Mesh, BadInputIsReported)
{
  EXPECT_EQ(find_mesh_error(tet_vertices, {}), "the mesh has no faces");
  EXPECT_NE(find_mesh_error(tet_vertices, std::vector<ivec3>{{0, 1, 9}}).find("vertex 9"), std::string::npos);
  std::vector<vec3> nan_vertices = tet_vertices;
  nan_vertices[2].x = NAN;
  EXPECT_NE(find_mesh_error(nan_vertices, tet_triangles).find("vertex 2"), std::string::npos);
}

TEST(Mesh, NonManifoldTrianglesAreSkippedNotFatal)
{
  /* Three triangles on one edge (0, 1): the third makes the edge complex. */
  const std::vector<vec3> vertices{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  const std::vector<ivec3> triangles{{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const ColliderMesh mesh(vertices, triangles);
  EXPECT_EQ(mesh.skipped_triangles_num(), 1);
  EXPECT_EQ(mesh.triangles_num(), 2);
}
