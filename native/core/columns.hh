#pragma once
/* A table of per-point values, one row per point and each attribute a span of columns side by
 * side (a bake cache frame, addon/hairdyn/cache.py), split into one flat array per attribute
 * as Blender's foreach_set takes them. */
#include <cstdint>
#include <vector>

namespace hairdyn {

struct ColumnSpan {
  float *out;    /* rows * width values */
  int64_t start; /* the table's first column of the span */
  int64_t width;
};

/* Copies each span of the (rows, table_width) row-major table into its output and checks
 * every value of the table (those of no span too), a block of rows at a time on the thread
 * pool (each block read from memory once): returns whether they are all finite. The outputs
 * are filled either way. */
bool split_columns(const float *table, int64_t rows, int64_t table_width,
                   const std::vector<ColumnSpan> &columns);

}  // namespace hairdyn
