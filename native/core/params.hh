#pragma once
/* Parameter structs describe themselves once: every solver's plain parameter struct has a
 *
 *   template<typename Fn> static void for_each_field(Fn &&fn);
 *
 * that calls fn(&Struct::field, ParamInfo{...}) for each field, in declaration order. The
 * bindings generate attribute access, range checks and a `fields()` table from it, and a
 * Python test checks that table against the add-on's PropertyGroup, so UI and solver cannot
 * drift apart. Field types: float, int32_t, bool, glm::vec3 (a 3-tuple in Python, min and max
 * apply to each component), or an enum class over int32_t (its names in `choices`, comma
 * separated, in value order). */
#include <cstdint>
#include <limits>

namespace hairdyn {

constexpr double unbounded = std::numeric_limits<double>::infinity();

struct ParamInfo {
  const char *name;        /* Python / property name, snake_case. */
  const char *symbol;      /* The paper's symbol ("k_θ"), or "" when the paper has none. */
  const char *unit;        /* SI unit ("N·m/rad"), "" when dimensionless. */
  double min;              /* Inclusive hard range, checked at the boundary. */
  double max;
  const char *description; /* One sentence for the tooltip, naming the paper's equation. */
  const char *choices = ""; /* For enums: "explicit,implicit". */
  /* What the add-on needs to show the field (the PropertyGroups are generated from this):
   * the panel shows value × display_scale in display_unit ("µN·m/rad"), so hair-sized SI
   * values read as ordinary numbers; the slider spans [soft_min, soft_max] (infinite: the
   * hard range); label is the short panel label ("" : derived from the name). */
  double display_scale = 1.0;
  const char *display_unit = "";
  double soft_min = -unbounded;
  double soft_max = unbounded;
  const char *label = "";

  /* Chained in the struct's for_each_field: ParamInfo{...}.shown_as(1e6, "µN·m/rad").soft(0, 10). */
  constexpr ParamInfo shown_as(const double scale, const char *unit_shown) const
  {
    ParamInfo info = *this;
    info.display_scale = scale;
    info.display_unit = unit_shown;
    return info;
  }
  constexpr ParamInfo soft(const double lo, const double hi) const
  {
    ParamInfo info = *this;
    info.soft_min = lo;
    info.soft_max = hi;
    return info;
  }
  constexpr ParamInfo labeled(const char *text) const
  {
    ParamInfo info = *this;
    info.label = text;
    return info;
  }
};

}  // namespace hairdyn
