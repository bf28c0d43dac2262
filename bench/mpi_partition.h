// The balanced block partition shared by the partitioned models of bench/mpi_membrane.cpp
// (membrane rows, plate node columns): rank r of size owns items [*first, *first + *count), the
// first n % size ranks one more.
#ifndef CEODE_BENCH_MPI_PARTITION_H_
#define CEODE_BENCH_MPI_PARTITION_H_

#include <algorithm>

namespace mpi_partition {

inline void BalancedRange(int n, int size, int rank, int* first, int* count) {
  const int base = n / size;
  const int extra = n % size;
  *count = base + (rank < extra ? 1 : 0);
  *first = rank * base + std::min(rank, extra);
}

}  // namespace mpi_partition

#endif  // CEODE_BENCH_MPI_PARTITION_H_
