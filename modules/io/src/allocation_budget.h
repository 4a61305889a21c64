// A per-thread ceiling on single allocations, set while MRPT deserialises a
// rawlog entry (rawlog_reader.cpp): MRPT reads a count and resizes a
// container before it reads the data, so a corrupt count would allocate
// (and fill) gigabytes before the short read is noticed. With a budget
// active, operator new refuses a request above it, or one that brings what
// the scope asked for in all above it, with std::bad_alloc before
// allocating, and remembers the size asked for.
#pragma once

#include <cstddef>

namespace carenav::io::detail {

class AllocationBudget {
 public:
  /** Active until destroyed (scopes nest: the inner one wins, the outer one
   *  comes back). 0 means no ceiling. */
  explicit AllocationBudget(size_t max_bytes);
  ~AllocationBudget();
  AllocationBudget(const AllocationBudget&) = delete;
  AllocationBudget& operator=(const AllocationBudget&) = delete;
  /** The largest request (or running total) refused while this scope was
   *  active; 0 if none. */
  size_t refused() const;

 private:
  size_t saved_budget_, saved_refused_, saved_total_;
};

}  // namespace carenav::io::detail
