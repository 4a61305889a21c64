// Line-based TCP for the live app: the robot bridge and the TCP intent
// source. Non-blocking, one peer at a time; lines end with '\n' ('\r'
// stripped); a line longer than max_line is an error (a peer that never
// sends a newline cannot grow memory without bound).
#pragma once

#include <cstdint>
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
  /** Reads what has arrived (waiting at most `timeout_ms`, taking at most
   *  `max_bytes` bytes off the socket: the rest waits for the next call) and
   *  appends the complete lines to `out`. Returns false once the peer has
   *  stopped sending (closed, or half-closed: the socket stays open for
   *  sendLine, so a peer that still reads gets the last words) or the
   *  connection broke (see `resetByPeer()`); then `pendingPartial()` tells
   *  whether it left half a line. Throws std::runtime_error for a line
   *  longer than `max_line` bytes. */
  bool readLines(std::vector<std::string>& out, int timeout_ms = 0, size_t max_bytes = SIZE_MAX);
  /** Sends one line ('\n' appended), waiting at most `timeout_ms` for room
   *  in the socket's buffer (a peer that stops reading cannot block the
   *  caller for longer); false when the peer is gone or did not take it. */
  bool sendLine(const std::string& line, int timeout_ms = 1000);
  /** The peer will send nothing more (it closed or half-closed). */
  bool peerDone() const { return peer_done_; }
  /** The connection ended with an error (reset by the peer, ...). */
  bool resetByPeer() const { return reset_; }
  /** Bytes of an unterminated line received before the peer closed. */
  const std::string& pendingPartial() const { return buf_; }
  void close();
  /** Half-closes: the peer reads end-of-file, this side can still read. */
  void shutdownWrite();
  /** Closes with a reset (RST) instead of an orderly end. */
  void abort();
  size_t max_line = 1 << 20;

 private:
  int fd_ = -1;
  bool peer_done_ = false, reset_ = false;
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

/** Peer text made safe to print on a terminal: bytes below 0x20, 0x7f and
 *  above (ESC, BEL, NUL, ...) as \xNN, a backslash as \\; at most
 *  `max_chars` characters of it, then "..." and the count left out. */
std::string printableText(const std::string& s, size_t max_chars = 80);

/** "HOST:PORT" or "PORT" (host `default_host`); throws std::invalid_argument. */
std::pair<std::string, int> parseHostPort(const std::string& s, const std::string& default_host);

}  // namespace carenav::navigation
