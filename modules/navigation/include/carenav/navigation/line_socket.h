// Line-based TCP for the live app: the robot bridge and the TCP intent
// source. Non-blocking, one peer at a time; lines end with '\n' ('\r'
// stripped); a line longer than max_line is an error (a peer that never
// sends a newline cannot grow memory without bound).
#pragma once

#include <string>
#include <vector>

namespace carenav::navigation {

class LineSocket {
 public:
  LineSocket() = default;
  explicit LineSocket(int fd);
  ~LineSocket();
  LineSocket(const LineSocket&) = delete;
  LineSocket& operator=(const LineSocket&) = delete;
  LineSocket(LineSocket&& o) noexcept;
  LineSocket& operator=(LineSocket&& o) noexcept;

  bool open() const { return fd_ >= 0; }
  /** Reads what has arrived (waiting at most `timeout_ms`) and appends
   *  the complete lines to `out`. Returns false once the peer has closed
   *  (then `pendingPartial()` tells whether it left half a line). Throws
   *  std::runtime_error for a line longer than `max_line` bytes. */
  bool readLines(std::vector<std::string>& out, int timeout_ms = 0);
  /** Sends one line ('\n' appended); false when the peer is gone. */
  bool sendLine(const std::string& line);
  /** Bytes of an unterminated line received before the peer closed. */
  const std::string& pendingPartial() const { return buf_; }
  void close();
  size_t max_line = 1 << 20;

 private:
  int fd_ = -1;
  std::string buf_;
};

/** Connects to HOST:PORT, retrying for up to `timeout_s`. Throws
 *  std::runtime_error naming the address when it cannot. */
LineSocket connectTcp(const std::string& host, int port, double timeout_s);

/** A listening TCP socket (SO_REUSEADDR) on HOST:PORT; port 0 picks a free
 *  one (see port()). Throws std::runtime_error naming the address. */
class TcpListener {
 public:
  TcpListener(const std::string& host, int port);
  ~TcpListener();
  TcpListener(const TcpListener&) = delete;
  TcpListener& operator=(const TcpListener&) = delete;
  int port() const { return port_; }
  /** A client if one is waiting (at most `timeout_ms`), else an unopened socket. */
  LineSocket accept(int timeout_ms = 0);

 private:
  int fd_ = -1;
  int port_ = 0;
};

/** "HOST:PORT" or "PORT" (host `default_host`); throws std::invalid_argument. */
std::pair<std::string, int> parseHostPort(const std::string& s, const std::string& default_host);

}  // namespace carenav::navigation
