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

struct ParamInfo {
  const char *name;        /* Python / property name, snake_case. */
  const char *symbol;      /* The paper's symbol ("k_θ"), or "" when the paper has none. */
  const char *unit;        /* SI unit ("N·m/rad"), "" when dimensionless. */
  double min;              /* Inclusive hard range, checked at the boundary. */
  double max;
  const char *description; /* One sentence for the tooltip, naming the paper's equation. */
  const char *choices = ""; /* For enums: "explicit,implicit". */
};

constexpr double unbounded = std::numeric_limits<double>::infinity();

}  // namespace hairdyn
