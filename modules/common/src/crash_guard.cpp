#include <carenav/common/crash_guard.h>

#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>

namespace carenav {

namespace {
constexpr size_t kCtx = 1024;
char g_context[kCtx] = {0};
volatile sig_atomic_t g_active = 0;

void writeAll(const char* s) {
  size_t n = std::strlen(s);
  while (n > 0) {
    const ssize_t w = ::write(STDERR_FILENO, s, n);
    if (w <= 0) return;
    s += w;
    n -= static_cast<size_t>(w);
  }
}

void onFatalSignal(int sig) {
  if (g_active) {
    writeAll("\ncarenav: error: ");
    writeAll(g_context);
    writeAll("\n");
    ::_exit(2);
  }
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}
}  // namespace

void installCrashGuard() {
  // An alternate stack, so that a stack overflow is reported too.
  static char altstack[64 * 1024];
  stack_t ss{};
  ss.ss_sp = altstack;
  ss.ss_size = sizeof altstack;
  ::sigaltstack(&ss, nullptr);
  struct sigaction sa {};
  sa.sa_handler = onFatalSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_ONSTACK | SA_RESETHAND;
  for (int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL}) ::sigaction(sig, &sa, nullptr);
}

size_t defaultMemoryLimitMB() {
  if (const char* e = std::getenv("CARENAV_MEMORY_LIMIT_MB"); e && *e)
    return static_cast<size_t>(std::strtoull(e, nullptr, 10));
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return 0;
  return static_cast<size_t>(pages / 1024 * page / 1024 * 3 / 4);
}

size_t limitAddressSpace(size_t megabytes) {
  if (megabytes == 0 || builtWithAddressSanitizer()) return 0;
  rlimit rl{};
  if (::getrlimit(RLIMIT_AS, &rl) != 0) return 0;
  rlim_t want = static_cast<rlim_t>(megabytes) * 1024 * 1024;
  if (rl.rlim_max != RLIM_INFINITY && want > rl.rlim_max) want = rl.rlim_max;
  rl.rlim_cur = want;
  if (::setrlimit(RLIMIT_AS, &rl) != 0) return 0;
  return static_cast<size_t>(want / 1024 / 1024);
}

CrashContext::CrashContext(const std::string& what) : had_saved_(g_active != 0) {
  std::memcpy(saved_, g_context, kSize);
  g_active = 0;
  const size_t n = std::min(what.size(), kCtx - 1);
  std::memcpy(g_context, what.data(), n);
  g_context[n] = 0;
  g_active = 1;
}

CrashContext::~CrashContext() {
  g_active = 0;
  std::memcpy(g_context, saved_, kSize);
  g_active = had_saved_ ? 1 : 0;
}

std::string CrashContext::current() { return g_active ? std::string(g_context) : std::string(); }

}  // namespace carenav
