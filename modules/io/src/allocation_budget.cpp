// See allocation_budget.h. The replaceable global operator new/delete
// ([new.delete.single], [new.delete.array]) are defined here, in the object
// file the rawlog reader needs, so every program that reads rawlogs has
// them; without an active budget they behave as the standard ones (malloc,
// the new-handler, std::bad_alloc). MRPT's aligned allocation function is
// replaced too (see the end of the file).
#include "allocation_budget.h"

#include <mrpt/core/aligned_allocator.h>

#include <cstdlib>
#include <new>

namespace {
thread_local size_t t_budget = 0;   // 0: no ceiling
thread_local size_t t_refused = 0;  // largest request refused in the scope
thread_local size_t t_total = 0;    // bytes asked for in the scope (frees not counted back)
}  // namespace

namespace carenav::io::detail {

AllocationBudget::AllocationBudget(size_t max_bytes)
    : saved_budget_(t_budget), saved_refused_(t_refused), saved_total_(t_total) {
  t_budget = max_bytes;
  t_refused = 0;
  t_total = 0;
}
AllocationBudget::~AllocationBudget() {
  t_budget = saved_budget_;
  t_refused = saved_refused_;
  t_total = saved_total_;
}
size_t AllocationBudget::refused() const { return t_refused; }

}  // namespace carenav::io::detail

namespace {
// A single request above the budget, or requests adding up to more than it
// (a corrupt count of small elements: a deque of a billion particles).
void checkBudget(std::size_t n) {
  if (t_budget == 0) return;
  if (n > t_budget || t_total > t_budget - n) {
    const size_t asked = n > t_budget ? n : t_total + n;
    if (asked > t_refused) t_refused = asked;
    throw std::bad_alloc();
  }
  t_total += n;
}
}  // namespace

void* operator new(std::size_t n) {
  checkBudget(n);
  for (;;) {
    if (void* p = std::malloc(n ? n : 1)) return p;
    std::new_handler h = std::get_new_handler();
    if (!h) throw std::bad_alloc();
    h();
  }
}
void* operator new[](std::size_t n) { return ::operator new(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

// Over-aligned types: the same, on aligned_alloc (whose blocks free() takes,
// as the standard aligned operator delete does).
void* operator new(std::size_t n, std::align_val_t al) {
  checkBudget(n);
  const auto a = static_cast<std::size_t>(al);
  const std::size_t rounded = (n + a - 1) / a * a;
  for (;;) {
    if (void* p = std::aligned_alloc(a, rounded ? rounded : a)) return p;
    std::new_handler h = std::get_new_handler();
    if (!h) throw std::bad_alloc();
    h();
  }
}
void* operator new[](std::size_t n, std::align_val_t al) { return ::operator new(n, al); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

// The nothrow forms too: every form is replaced, so whatever pairs a
// library makes (get_temporary_buffer: nothrow new, plain delete) the block
// comes from malloc and goes back to free. (Found by AddressSanitizer's
// alloc-dealloc-mismatch: its own nothrow new met this file's delete.)
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return ::operator new(n);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  return ::operator new(n, std::nothrow);
}
void* operator new(std::size_t n, std::align_val_t al, const std::nothrow_t&) noexcept {
  try {
    return ::operator new(n, al);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t n, std::align_val_t al, const std::nothrow_t&) noexcept {
  return ::operator new(n, al, std::nothrow);
}
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }

// MRPT's containers of scans and images (mrpt::aligned_std_vector) do not
// allocate through operator new but through mrpt::aligned_malloc, and use
// the block without checking it: a corrupt count that fails to allocate
// becomes a write through a null pointer (the crash MRPT's reader had on
// corrupt rawlogs). This definition takes the place of libmrpt-core's for the
// whole program (the executable's symbol comes first in the dynamic
// linker's lookup): the same block as MRPT's (aligned_alloc, size rounded up
// to the alignment, released by mrpt::aligned_free, i.e. free()), but a
// request above the budget, or one that cannot be met, throws std::bad_alloc
// instead of returning null.
namespace mrpt {
void* aligned_malloc(size_t size, size_t alignment) {
  checkBudget(size);
  if (alignment != 0 && size % alignment != 0) size = (size / alignment + 1) * alignment;
  void* p = ::aligned_alloc(alignment, size);
  if (!p && size != 0) throw std::bad_alloc();
  return p;
}
}  // namespace mrpt
