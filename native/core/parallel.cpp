#include "core/parallel.hh"

#include <omp.h>

namespace hairdyn {

void set_thread_num(const int thread_num)
{
  omp_set_num_threads(thread_num > 0 ? thread_num : omp_get_num_procs());
}

int thread_num()
{
  return omp_get_max_threads();
}

}  // namespace hairdyn
