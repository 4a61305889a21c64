// The one distance transform of the project: exact squared Euclidean
// distances on a grid, two passes of the 1D lower-envelope algorithm of
// [Felzenszwalb12, Sec. 2.1, Alg. DT(f)]. Used by the local cost map, the
// global planner, the localiser's likelihood field, room centres (places)
// and the simulator's truth clearance.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace carenav {

/** Squared distance, in cells², from every cell of a row-major nx x ny grid
 *  to the nearest cell where `source` is 0 (an obstacle, say); +infinity
 *  everywhere when no cell is 0. Exact: the values are whole numbers (in
 *  float up to 2^24 cells², a 2896-cell diagonal). `Real` is float or double:
 *  float for the maps rebuilt every control cycle (half the memory), double
 *  for whole maps read once. */
template <class Real = double>
std::vector<Real> squaredDistanceTransform(const std::vector<uint8_t>& source, int nx, int ny);

extern template std::vector<float> squaredDistanceTransform<float>(const std::vector<uint8_t>&, int,
                                                                   int);
extern template std::vector<double> squaredDistanceTransform<double>(const std::vector<uint8_t>&,
                                                                     int, int);

}  // namespace carenav
