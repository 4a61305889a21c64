// Line-based TCP (see line_socket.h).
#include <carenav/runtime/line_socket.h>

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <thread>

namespace carenav::navigation {

namespace {

sockaddr_in resolve(const std::string& host, int port) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(port));
  if (inet_pton(AF_INET, host.c_str(), &a.sin_addr) == 1) return a;
  addrinfo hints{}, *res = nullptr;
  hints.ai_family = AF_INET;
  if (getaddrinfo(host.c_str(), nullptr, &hints, &res) != 0 || !res)
    throw std::runtime_error(host + ": unknown host");
  a.sin_addr = reinterpret_cast<sockaddr_in*>(res->ai_addr)->sin_addr;
  freeaddrinfo(res);
  return a;
}

void setNonBlocking(int fd) { fcntl(fd, F_SETFL, fcntl(fd, F_GETFL, 0) | O_NONBLOCK); }

}  // namespace

LineSocket::LineSocket(int fd) : fd_(fd) {
  if (fd_ >= 0) {
    setNonBlocking(fd_);
    int one = 1;
    setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  }
}
LineSocket::~LineSocket() { close(); }
LineSocket::LineSocket(LineSocket&& o) noexcept
    : fd_(o.fd_), peer_done_(o.peer_done_), reset_(o.reset_), buf_(std::move(o.buf_)) {
  max_line = o.max_line;
  o.fd_ = -1;
}
LineSocket& LineSocket::operator=(LineSocket&& o) noexcept {
  if (this != &o) {
    close();
    fd_ = o.fd_;
    peer_done_ = o.peer_done_;
    reset_ = o.reset_;
    buf_ = std::move(o.buf_);
    max_line = o.max_line;
    o.fd_ = -1;
  }
  return *this;
}
void LineSocket::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

void LineSocket::shutdownWrite() {
  if (fd_ >= 0) ::shutdown(fd_, SHUT_WR);
}
void LineSocket::abort() {
  if (fd_ < 0) return;
  linger l{1, 0};
  setsockopt(fd_, SOL_SOCKET, SO_LINGER, &l, sizeof l);
  close();
}

bool LineSocket::readLines(std::vector<std::string>& out, int timeout_ms, size_t max_bytes) {
  if (fd_ < 0 || peer_done_) return false;
  pollfd p{fd_, POLLIN, 0};
  if (::poll(&p, 1, timeout_ms) <= 0) return true;
  char b[8192];
  size_t taken = 0;
  while (taken < max_bytes) {
    const ssize_t r = ::recv(fd_, b, std::min(sizeof b, max_bytes - taken), 0);
    if (r == 0) {
      // Closed or half-closed: nothing more comes, but the peer may still
      // read (the caller's last command and 'stop' must reach it).
      peer_done_ = true;
      break;
    }
    if (r < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) break;
      if (errno == EINTR) continue;
      reset_ = true;
      peer_done_ = true;
      close();
      break;
    }
    buf_.append(b, static_cast<size_t>(r));
    taken += static_cast<size_t>(r);
  }
  size_t start = 0, nl;
  while ((nl = buf_.find('\n', start)) != std::string::npos) {
    if (nl - start > max_line) {
      buf_.clear();
      throw std::runtime_error("a line longer than " + std::to_string(max_line) + " bytes");
    }
    std::string line = buf_.substr(start, nl - start);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    out.push_back(std::move(line));
    start = nl + 1;
  }
  buf_.erase(0, start);
  if (buf_.size() > max_line) {
    buf_.clear();
    throw std::runtime_error("a line longer than " + std::to_string(max_line) + " bytes");
  }
  return !peer_done_;
}

bool LineSocket::sendLine(const std::string& line, int timeout_ms) {
  if (fd_ < 0) return false;
  const std::string s = line + "\n";
  const auto t0 = std::chrono::steady_clock::now();
  size_t done = 0;
  while (done < s.size()) {
    const ssize_t w = ::send(fd_, s.data() + done, s.size() - done, MSG_NOSIGNAL);
    if (w < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) {
      const int spent = static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(
                                             std::chrono::steady_clock::now() - t0)
                                             .count());
      if (spent >= timeout_ms) return false;  // the peer does not read
      pollfd p{fd_, POLLOUT, 0};
      ::poll(&p, 1, timeout_ms - spent);
      continue;
    }
    if (w <= 0) {
      reset_ = reset_ || errno == ECONNRESET || errno == EPIPE;
      close();
      return false;
    }
    done += static_cast<size_t>(w);
  }
  return true;
}

LineSocket connectTcp(const std::string& host, int port, double timeout_s) {
  const sockaddr_in a = resolve(host, port);
  const auto t0 = std::chrono::steady_clock::now();
  for (;;) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0) throw std::runtime_error("cannot create a socket");
    if (::connect(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) == 0) return LineSocket(fd);
    const int err = errno;
    ::close(fd);
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > timeout_s)
      throw std::runtime_error(host + ":" + std::to_string(port) +
                               ": cannot connect: " + std::strerror(err));
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
}

TcpListener::TcpListener(const std::string& host, int port) {
  const sockaddr_in a = resolve(host, port);
  fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd_ < 0) throw std::runtime_error("cannot create a socket");
  int one = 1;
  setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0 || ::listen(fd_, 1) != 0) {
    const std::string e = std::strerror(errno);
    ::close(fd_);
    fd_ = -1;
    throw std::runtime_error(host + ":" + std::to_string(port) + ": cannot listen: " + e);
  }
  sockaddr_in got{};
  socklen_t len = sizeof got;
  getsockname(fd_, reinterpret_cast<sockaddr*>(&got), &len);
  port_ = ntohs(got.sin_port);
  setNonBlocking(fd_);
}
TcpListener::~TcpListener() {
  if (fd_ >= 0) ::close(fd_);
}
LineSocket TcpListener::accept(int timeout_ms) {
  pollfd p{fd_, POLLIN, 0};
  if (::poll(&p, 1, timeout_ms) <= 0) return LineSocket();
  const int c = ::accept(fd_, nullptr, nullptr);
  return LineSocket(c);
}

std::string printableText(const std::string& s, size_t max_chars) {
  std::string o;
  size_t i = 0;
  for (; i < s.size() && o.size() < max_chars; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c == '\\') {
      o += "\\\\";
    } else if (c < 0x20 || c >= 0x7f) {
      char b[8];
      std::snprintf(b, sizeof b, "\\x%02x", c);
      o += b;
    } else {
      o += static_cast<char>(c);
    }
  }
  if (i < s.size()) o += "... (" + std::to_string(s.size() - i) + " more bytes)";
  return o;
}

std::pair<std::string, int> parseHostPort(const std::string& s, const std::string& default_host) {
  const auto colon = s.rfind(':');
  const std::string host = colon == std::string::npos ? default_host : s.substr(0, colon);
  const std::string port = colon == std::string::npos ? s : s.substr(colon + 1);
  char* end = nullptr;
  const long p = std::strtol(port.c_str(), &end, 10);
  if (port.empty() || *end != '\0' || p < 0 || p > 65535 || host.empty())
    throw std::invalid_argument("'" + s + "' is not HOST:PORT or PORT");
  return {host, static_cast<int>(p)};
}

}  // namespace carenav::navigation
