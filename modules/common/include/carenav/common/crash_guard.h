// Last-resort guard for third-party code that crashes on corrupt input.
//
// MRPT's deserialisers trust the size fields they read: a corrupt rawlog can
// make them allocate absurd amounts of memory, or write through the null
// pointer MRPT's aligned allocator returns when that allocation fails. carenav
// cannot validate MRPT's binary layout ahead of MRPT, so readers of outside
// input name what they are reading (a CrashContext), and the executable turns
// a fatal signal raised meanwhile into the usual bad-input answer: a message
// naming the file and the entry, and exit code 2.
#pragma once

#include <cstddef>
#include <string>

namespace carenav {

/** Installs handlers for SIGSEGV, SIGBUS, SIGFPE and SIGILL. While a
 *  CrashContext is active they print "carenav: error: <context>" and exit
 *  with code 2; otherwise they re-raise the signal (a real bug stays a crash). */
void installCrashGuard();

/** True in a build with AddressSanitizer (CARENAV_SANITIZE, CARENAV_FUZZ). */
constexpr bool builtWithAddressSanitizer() {
#if defined(__SANITIZE_ADDRESS__)
  return true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
  return true;
#else
  return false;
#endif
#else
  return false;
#endif
}

/** Caps the process address space (setrlimit RLIMIT_AS) so that a corrupt
 *  size field makes an allocation fail (std::bad_alloc, reported as corrupt
 *  input) instead of exhausting the machine. `megabytes` 0 keeps no cap.
 *  Returns the cap applied, in MB. Under AddressSanitizer, which reserves
 *  terabytes of shadow memory, no cap is set (0): ASan's own allocator
 *  limits apply instead. */
size_t limitAddressSpace(size_t megabytes);

/** Default cap: $CARENAV_MEMORY_LIMIT_MB if set (0: none), else 3/4 of the
 *  physical memory. */
size_t defaultMemoryLimitMB();

/** Names what is being read while it is in scope (nesting restores the
 *  outer context). The text is copied into a fixed buffer: cheap enough to
 *  set once per rawlog entry. */
class CrashContext {
 public:
  explicit CrashContext(const std::string& what);
  ~CrashContext();
  CrashContext(const CrashContext&) = delete;
  CrashContext& operator=(const CrashContext&) = delete;
  /** The active context, or "" (for tests). */
  static std::string current();

 private:
  static constexpr size_t kSize = 1024;
  char saved_[kSize];
  bool had_saved_;
};

}  // namespace carenav
