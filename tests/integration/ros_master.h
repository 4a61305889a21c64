// A rosmaster of its own on a free loopback port (never the default 11311)
// for the tests and benchmarks of the ROS nodes, and processes to run
// against it. Only with the ROS part.
#pragma once

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace carenav_ros_test {

namespace fs = std::filesystem;

/** A free TCP port on the loopback (never 11311). */
inline int freePort() {
  for (;;) {
    const int s = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t n = sizeof a;
    ::bind(s, reinterpret_cast<sockaddr*>(&a), n);
    ::getsockname(s, reinterpret_cast<sockaddr*>(&a), &n);
    ::close(s);
    const int port = ntohs(a.sin_port);
    if (port != 11311) return port;
  }
}

inline bool accepts(int port) {
  const int s = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool ok = ::connect(s, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  ::close(s);
  return ok;
}

inline pid_t spawn(std::vector<std::string> args, const fs::path& log) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  pid_t pid = -1;
  posix_spawnp(&pid, argv[0], &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  return pid;
}

/** The child has not ended (an ended one is reaped here, never waited on
 *  forever as a zombie that kill(pid, 0) still finds). */
inline bool running(pid_t pid) { return ::waitpid(pid, nullptr, WNOHANG) == 0; }

inline int waitExit(pid_t pid) {
  int st = 0;
  ::waitpid(pid, &st, 0);
  return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
}

/** A rosmaster of its own for the test, and the environment that finds it. */
class RosMaster {
 public:
  explicit RosMaster(const fs::path& parent)
      : port_(freePort()), dir_(parent / ("ros_" + std::to_string(port_))) {
    fs::create_directories(dir_);
    const std::string uri = "http://127.0.0.1:" + std::to_string(port_);
    ::setenv("ROS_MASTER_URI", uri.c_str(), 1);
    ::setenv("ROS_IP", "127.0.0.1", 1);
    ::setenv("ROS_HOME", dir_.c_str(), 1);
    pid_ = spawn({"rosmaster", "--core", "-p", std::to_string(port_)}, dir_ / "master.log");
    while (pid_ > 0 && !accepts(port_) && ::kill(pid_, 0) == 0)
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ~RosMaster() {
    if (pid_ > 0) ::kill(pid_, SIGTERM), waitExit(pid_);
  }
  bool up() const { return pid_ > 0 && accepts(port_); }
  const fs::path& dir() const { return dir_; }

 private:
  int port_;
  fs::path dir_;
  pid_t pid_ = -1;
};

}  // namespace carenav_ros_test
