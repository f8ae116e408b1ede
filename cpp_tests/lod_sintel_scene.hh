#pragma once
/* Ward & Lin 2003, Tables 1 and 2, as a scene (the level-of-detail benchmark and its test): a
 * groom of 9,120 strands (Sintel's 228 guides, 40 children around each within 1.2 cm, 32
 * points per strand, Kurihara 1993 §4's cluster model) on Sintel's bust as the collider, wind
 * blowing, a camera close to the face or zooming out to 8 m. Read from the shared data folder;
 * `loaded` is false when the assets are missing. */
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "collision_test_shapes.hh"
#include "core/wind.hh"
#include "groom/children_kurihara1993.hh"
#include "groom/frames.hh"
#include "lod/lod_params_ward2003.hh"
#include "lod_scenes.hh"

namespace hairdyn::test {

constexpr float sintel_scale = 0.015f; /* The assets are about 40 units tall: a 0.6 m bust. */
constexpr float sintel_frame_dt = 1.0f / 24.0f;
constexpr int sintel_frames_num = 24;

/* File (Y up) to Blender (Z up) axes, as the add-on's importer does, and to meters. */
inline vec3 sintel_to_scene(const vec3 &p)
{
  return sintel_scale * vec3(p.x, -p.z, p.y);
}

struct SintelScene {
  std::vector<int32_t> offsets;
  std::vector<vec3> positions;
  std::shared_ptr<ColliderSet> colliders;
  vec3 head_centre{ 0.0f };
  float mean_length = 0.0f;
  bool loaded = false;
};

inline const SintelScene &sintel()
{
  static SintelScene scene = [] {
    SintelScene s;
    std::ifstream file(std::string(sintel_folder) + "/sintel_hair.tfx", std::ios::binary);
    TestMesh bust;
    if (!file || !read_obj(sintel_bust_path, bust)) {
      return s;
    }
    const std::vector<char> data((std::istreambuf_iterator<char>(file)),
                                 std::istreambuf_iterator<char>());
    /* TressFX 4.0: version, strands, points per strand, then the positions' offset. */
    uint32_t guides_num = 0, points_num = 0, positions_offset = 0;
    std::memcpy(&guides_num, data.data() + 4, 4);
    std::memcpy(&points_num, data.data() + 8, 4);
    std::memcpy(&positions_offset, data.data() + 12, 4);
    std::vector<int32_t> guide_offsets{ 0 };
    std::vector<vec3> guides;
    for (uint32_t g = 0; g < guides_num; g++) {
      for (uint32_t i = 0; i < points_num; i++) {
        float xyzw[4];
        std::memcpy(xyzw, data.data() + positions_offset + 16 * (g * points_num + i), 16);
        guides.push_back(sintel_to_scene(vec3(xyzw[0], xyzw[1], xyzw[2])));
      }
      guide_offsets.push_back(int32_t(guides.size()));
    }
    std::vector<mat3> frames(guides_num);
    compute_root_frames(guide_offsets, guides, {}, frames);
    /* Kurihara 1993 §4's cluster model: 40 strands around each guide, within 1.2 cm. */
    ChildHairs children = ChildHairs::around_guides(guide_offsets, 40, 0.012f, 7);
    children.update(guides, frames);
    s.offsets.assign(children.curve_offsets().begin(), children.curve_offsets().end());
    s.positions.assign(children.positions().begin(), children.positions().end());
    for (vec3 &v : bust.vertices) {
      v = sintel_to_scene(v);
    }
    const ColliderMesh mesh(bust.vertices, bust.triangles);
    s.colliders = std::make_shared<ColliderSet>();
    s.colliders->add(
        std::make_shared<Collider>(mesh, Span<int32_t>(), Span<int32_t>(), CollisionParams()));
    vec3 root_sum(0.0f);
    double length = 0.0;
    for (size_t c = 0; c + 1 < s.offsets.size(); c++) {
      root_sum += s.positions[size_t(s.offsets[c])];
      for (int32_t i = s.offsets[c] + 1; i < s.offsets[c + 1]; i++) {
        length += double(glm::length(s.positions[size_t(i)] - s.positions[size_t(i - 1)]));
      }
    }
    const float curves = float(s.offsets.size() - 1);
    s.head_centre = root_sum / curves - vec3(0.0f, 0.0f, 0.05f);
    s.mean_length = float(length / double(curves));
    s.loaded = true;
    return s;
  }();
  return scene;
}

inline WindParams sintel_wind()
{
  WindParams w;
  w.speed = 3.0f;
  w.turbulence = 0.5f;
  return w;
}

inline LodParams sintel_lod_params()
{
  LodParams params;
  params.strips_num = 110; /* Ward's scene: 110 strips for 9,350 strands. */
  params.strip_splits = 1;
  params.cluster_min_radius = 0.01f;
  params.min_group_strands = 3;
  params.skeleton_points = 8; /* Ward's skeletons have 6 control points on average. */
  params.distance_near = 0.5f;
  params.distance_far = 6.0f;
  return params;
}

/* Camera for frame f: close to the face, or zooming out to 8 m. */
inline mat4 sintel_camera(const SintelScene &s, const int frame, const bool zoom_out)
{
  const float distance =
      zoom_out ? glm::mix(0.45f, 8.0f, float(frame) / float(sintel_frames_num - 1)) : 0.45f;
  return camera_view_projection(s.head_centre + vec3(0.0f, -distance, 0.05f), s.head_centre);
}

}  // namespace hairdyn::test
