/* hairdyn._native: every line of pybind11, and nothing else.
 *
 * Arrays cross the boundary without copies: (N, 3) float32 numpy arrays become Span<vec3>
 * over the same memory, and solver buffers come back as numpy views whose base keeps the
 * solver alive. Everything a caller can get wrong is checked here and raised as ValueError;
 * the core behind it assumes valid input. Native work runs with the GIL released. */
#include "bindings/arrays.hh"

PYBIND11_MODULE(_native, m)
{
  using namespace hairdyn::bindings;

  m.doc() = "hairdyn native solver core";
  m.attr("__version__") = "0.1.0";

  bind_groom(m);
  bind_collision(m);
  bind_strands(m);
  bind_lcp(m);
  bind_volume(m);
  bind_ssv(m);
  bind_lod(m);
}
