#include "core/columns.hh"

#include <cstring>

#include "core/parallel.hh"

namespace hairdyn {

/* One span's values of the table's rows `rows`; W > 0: its width, known here (a memcpy call
 * per row was most of the time), 0: span.width. */
template<int W>
static void copy_rows(const float *table, const int64_t table_width, const ColumnSpan &span,
                      const IndexRange rows)
{
  const int64_t width = W > 0 ? W : span.width;
  for (int64_t row = rows.start; row < rows.one_after_last(); row++) {
    const float *from = table + row * table_width + span.start;
    float *to = span.out + row * width;
    for (int64_t j = 0; j < width; j++) {
      to[j] = from[j];
    }
  }
}

bool split_columns(const float *table, const int64_t rows, const int64_t table_width,
                   const std::vector<ColumnSpan> &columns)
{
  return parallel_reduce(
      rows, 8192, true,
      [&](const IndexRange range) {
        /* Not finite: every exponent bit set (the test vectorises; std::isfinite does not). */
        uint32_t nonfinite = 0;
        const float *first = table + range.start * table_width;
        for (int64_t i = 0; i < range.size * table_width; i++) {
          uint32_t bits;
          std::memcpy(&bits, first + i, sizeof(bits));
          nonfinite |= uint32_t((bits & 0x7f800000u) == 0x7f800000u);
        }
        for (const ColumnSpan &span : columns) {
          /* The widths attributes have: scalars and vectors. */
          switch (span.width) {
            case 1:
              copy_rows<1>(table, table_width, span, range);
              break;
            case 3:
              copy_rows<3>(table, table_width, span, range);
              break;
            default:
              copy_rows<0>(table, table_width, span, range);
          }
        }
        return nonfinite == 0;
      },
      [](const bool a, const bool b) { return a && b; });
}

}  // namespace hairdyn
