// A ROS bag (format 2.0) read front to back, one message at a time, without
// its index: a bag cut short (a recorder killed, a copy broken off) is read
// up to where it breaks, which the library's indexed reader cannot do.
// Chunks: none, lz4 or bz2. [ROSbag]
#pragma once

#include <cstdint>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace carenav::ros {

/** A bag's connection: one topic with one message type. */
struct BagConnection {
  uint32_t id = 0;
  std::string topic, type, md5sum;
};

/** One message: its connection, the time it was recorded and its bytes
 *  (valid until the next call of BagFile::next). */
struct BagMessage {
  const BagConnection* connection = nullptr;
  uint32_t sec = 0, nsec = 0;
  const uint8_t* data = nullptr;
  uint32_t size = 0;
  uint64_t offset = 0;  ///< byte of the file where the message's record starts (its chunk's)
};

/** A bag that cannot be read on; `offset` is the byte where it broke. */
struct BagBroken {
  std::string what;
  uint64_t offset = 0;
};

class BagFile {
 public:
  /** Opens the bag and reads its header; throws BagBroken when it is not
   *  a bag of format 2.0. */
  explicit BagFile(const std::string& path);
  /** The next message; false at the end of the data. Throws BagBroken. */
  bool next(BagMessage& out);
  uint64_t position() const { return pos_; }
  uint64_t size() const { return size_; }
  size_t messages() const { return messages_; }

 private:
  struct Record {
    std::map<std::string, std::string> fields;
    uint64_t data_pos = 0;
    uint32_t data_len = 0;
    bool cut = false;  ///< the file ends inside the data (data_len: what is there)
  };
  bool readRecord(Record& r);  // false: clean end of file
  void readBytes(uint64_t at, void* buf, size_t n, const char* what);
  void loadChunk(const Record& r, uint64_t at);
  bool nextInChunk(BagMessage& out);
  void addConnection(const std::map<std::string, std::string>& header, const uint8_t* data,
                     uint32_t len, uint64_t at);

  std::ifstream in_;
  uint64_t size_ = 0, pos_ = 0;
  std::map<uint32_t, std::unique_ptr<BagConnection>> connections_;
  std::vector<uint8_t> chunk_;
  size_t chunk_pos_ = 0;
  uint64_t chunk_at_ = 0;
  size_t messages_ = 0;
  bool chunk_cut_ = false;  // the loaded chunk is the file's cut-off end
};

/** The header fields of a record ("name=value" each, length-prefixed). */
std::map<std::string, std::string> parseBagHeader(const uint8_t* p, size_t n);

}  // namespace carenav::ros
