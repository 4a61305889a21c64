#include "bag_file.h"

#include <bzlib.h>
#include <roslz4/lz4s.h>

#include <cstring>
#include <filesystem>

namespace carenav::ros {

namespace {

constexpr char kMagic[] = "#ROSBAG V2.0\n";
constexpr size_t kMagicLen = sizeof(kMagic) - 1;
constexpr uint32_t kMaxHeader = 1u << 20;  // a record header is a few fields
constexpr uint32_t kMaxChunk = 1u << 30;   // uncompressed chunk: 1 GiB at most

enum Op : uint8_t {
  kMsgData = 0x02,
  kBagHeader = 0x03,
  kIndexData = 0x04,
  kChunk = 0x05,
  kChunkInfo = 0x06,
  kConnection = 0x07
};

uint32_t le32(const uint8_t* p) {
  return uint32_t{p[0]} | uint32_t{p[1]} << 8 | uint32_t{p[2]} << 16 | uint32_t{p[3]} << 24;
}

uint8_t opOf(const std::map<std::string, std::string>& f, uint64_t at) {
  const auto it = f.find("op");
  if (it == f.end() || it->second.size() != 1)
    throw BagBroken{"a record without its 'op' field (corrupt data)", at};
  return static_cast<uint8_t>(it->second[0]);
}

uint32_t u32Field(const std::map<std::string, std::string>& f, const char* name, uint64_t at) {
  const auto it = f.find(name);
  if (it == f.end() || it->second.size() != 4)
    throw BagBroken{std::string("a record without its '") + name + "' field (corrupt data)", at};
  return le32(reinterpret_cast<const uint8_t*>(it->second.data()));
}

}  // namespace

std::map<std::string, std::string> parseBagHeader(const uint8_t* p, size_t n) {
  std::map<std::string, std::string> out;
  size_t i = 0;
  while (i < n) {
    if (n - i < 4) throw std::runtime_error("a header field cut short");
    const uint32_t len = le32(p + i);
    i += 4;
    if (len > n - i) throw std::runtime_error("a header field longer than its header");
    const std::string field(reinterpret_cast<const char*>(p + i), len);
    i += len;
    const size_t eq = field.find('=');
    if (eq == std::string::npos) throw std::runtime_error("a header field without '='");
    out[field.substr(0, eq)] = field.substr(eq + 1);
  }
  return out;
}

BagFile::BagFile(const std::string& path) : in_(path, std::ios::binary) {
  if (!in_) throw BagBroken{"cannot open the bag for reading", 0};
  std::error_code ec;
  size_ = std::filesystem::file_size(path, ec);
  char magic[kMagicLen] = {};
  in_.read(magic, kMagicLen);
  if (in_.gcount() != static_cast<std::streamsize>(kMagicLen) ||
      std::memcmp(magic, kMagic, kMagicLen) != 0)
    throw BagBroken{"not a ROS bag of format 2.0 (no '#ROSBAG V2.0' line at its start)", 0};
  pos_ = kMagicLen;
  Record r;
  if (!readRecord(r) || opOf(r.fields, kMagicLen) != kBagHeader)
    throw BagBroken{"no bag header record after the format line", kMagicLen};
  pos_ = r.data_pos + r.data_len;
}

void BagFile::readBytes(uint64_t at, void* buf, size_t n, const char* what) {
  if (at > size_ || n > size_ - at)
    throw BagBroken{std::string("the file ends inside ") + what +
                        " (truncated, or a corrupt length field reads past the end)",
                    at};
  in_.clear();
  in_.seekg(static_cast<std::streamoff>(at));
  in_.read(static_cast<char*>(buf), static_cast<std::streamsize>(n));
  if (in_.gcount() != static_cast<std::streamsize>(n))
    throw BagBroken{std::string("cannot read ") + what, at};
}

bool BagFile::readRecord(Record& r) {
  const uint64_t at = pos_;
  if (at == size_) return false;
  uint8_t len[4];
  readBytes(at, len, 4, "a record's header length");
  const uint32_t hlen = le32(len);
  if (hlen > kMaxHeader) throw BagBroken{"a record header length beyond 1 MiB (corrupt data)", at};
  std::vector<uint8_t> head(hlen + 4);
  readBytes(at + 4, head.data(), head.size(), "a record's header");
  try {
    r.fields = parseBagHeader(head.data(), hlen);
  } catch (const std::exception& e) {
    throw BagBroken{std::string("corrupt record header (") + e.what() + ")", at};
  }
  r.data_len = le32(head.data() + hlen);
  r.data_pos = at + 8 + hlen;
  if (r.data_pos > size_ || r.data_len > size_ - r.data_pos) {
    // An uncompressed chunk cut off: the records in what is there are read.
    const auto comp = r.fields.find("compression");
    if (r.data_pos > size_ || opOf(r.fields, at) != kChunk || comp == r.fields.end() ||
        comp->second != "none")
      throw BagBroken{"the file ends inside a record's data (truncated, or a corrupt length)", at};
    r.data_len = static_cast<uint32_t>(size_ - r.data_pos);
    r.cut = true;
  }
  return true;
}

void BagFile::loadChunk(const Record& r, uint64_t at) {
  const auto comp = r.fields.find("compression");
  const uint32_t raw = u32Field(r.fields, "size", at);
  if (comp == r.fields.end()) throw BagBroken{"a chunk without its compression field", at};
  if (raw > kMaxChunk) throw BagBroken{"a chunk size beyond 1 GiB (corrupt data)", at};
  std::vector<uint8_t> data(r.data_len);
  readBytes(r.data_pos, data.data(), data.size(), "a chunk");
  if (comp->second == "none") {
    if (raw != r.data_len && !r.cut)
      throw BagBroken{"a chunk whose size disagrees with its data", at};
    chunk_ = std::move(data);
  } else if (comp->second == "lz4" || comp->second == "bz2") {
    chunk_.assign(raw, 0);
    unsigned int got = raw;
    const bool ok =
        comp->second == "lz4"
            ? roslz4_buffToBuffDecompress(reinterpret_cast<char*>(data.data()), r.data_len,
                                          reinterpret_cast<char*>(chunk_.data()), &got) == 0
            : BZ2_bzBuffToBuffDecompress(reinterpret_cast<char*>(chunk_.data()), &got,
                                         reinterpret_cast<char*>(data.data()), r.data_len, 0,
                                         0) == BZ_OK;
    if (!ok || got != raw)
      throw BagBroken{"a " + comp->second + " chunk that does not decompress (corrupt data)", at};
  } else {
    throw BagBroken{"a chunk with unknown compression '" + comp->second.substr(0, 16) + "'", at};
  }
  chunk_pos_ = 0;
  chunk_at_ = at;
  chunk_cut_ = r.cut;
}

void BagFile::addConnection(const std::map<std::string, std::string>& header, const uint8_t* data,
                            uint32_t len, uint64_t at) {
  const uint32_t id = u32Field(header, "conn", at);
  if (connections_.count(id)) return;
  std::map<std::string, std::string> desc;
  try {
    desc = parseBagHeader(data, len);
  } catch (const std::exception& e) {
    throw BagBroken{std::string("corrupt connection record (") + e.what() + ")", at};
  }
  auto c = std::make_unique<BagConnection>();
  c->id = id;
  const auto topic = header.find("topic");
  c->topic = topic != header.end() ? topic->second : desc["topic"];
  c->type = desc["type"];
  c->md5sum = desc["md5sum"];
  connections_[id] = std::move(c);
}

// The next message of the loaded chunk (connections in it are taken in).
bool BagFile::nextInChunk(BagMessage& out) {
  while (chunk_pos_ < chunk_.size()) {
    const uint64_t at = chunk_at_;
    const size_t left = chunk_.size() - chunk_pos_;
    const uint8_t* p = chunk_.data() + chunk_pos_;
    const char* past = chunk_cut_ ? "the file ends inside a chunk (truncated)"
                                  : "a record inside a chunk runs past the chunk (corrupt data)";
    if (left < 4 || le32(p) > left - 4 || left - 4 - le32(p) < 4) throw BagBroken{past, at};
    const uint32_t hlen = le32(p);
    const uint32_t dlen = le32(p + 4 + hlen);
    if (dlen > left - 8 - hlen) throw BagBroken{past, at};
    std::map<std::string, std::string> h;
    try {
      h = parseBagHeader(p + 4, hlen);
    } catch (const std::exception& e) {
      throw BagBroken{std::string("corrupt record header in a chunk (") + e.what() + ")", at};
    }
    const uint8_t* data = p + 8 + hlen;
    chunk_pos_ += 8 + hlen + dlen;
    const uint8_t op = opOf(h, at);
    if (op == kConnection) {
      addConnection(h, data, dlen, at);
    } else if (op == kMsgData) {
      const auto c = connections_.find(u32Field(h, "conn", at));
      const auto time = h.find("time");
      if (c == connections_.end())
        throw BagBroken{"a message of a connection never declared (corrupt data)", at};
      if (time == h.end() || time->second.size() != 8)
        throw BagBroken{"a message without its time (corrupt data)", at};
      const auto* tp = reinterpret_cast<const uint8_t*>(time->second.data());
      out = BagMessage{c->second.get(), le32(tp), le32(tp + 4), data, dlen, at};
      ++messages_;
      return true;
    }
  }
  return false;
}

bool BagFile::next(BagMessage& out) {
  for (;;) {
    if (nextInChunk(out)) return true;
    if (chunk_cut_) throw BagBroken{"the file ends inside a chunk (truncated)", chunk_at_};
    const uint64_t at = pos_;
    Record r;
    if (!readRecord(r)) return false;
    pos_ = r.data_pos + r.data_len;
    const uint8_t op = opOf(r.fields, at);
    if (op == kChunk) {
      loadChunk(r, at);
    } else if (op == kConnection) {
      std::vector<uint8_t> data(r.data_len);
      readBytes(r.data_pos, data.data(), data.size(), "a connection record");
      addConnection(r.fields, data.data(), r.data_len, at);
    } else if (op == kMsgData) {
      // Outside a chunk: a bag whose recorder was killed before it closed
      // the chunk (its length still 0) continues with bare records.
      chunk_.resize(pos_ - at);
      readBytes(at, chunk_.data(), chunk_.size(), "a message");
      chunk_pos_ = 0;
      chunk_at_ = at;
    } else if (op != kIndexData && op != kChunkInfo && op != kBagHeader) {
      throw BagBroken{"a record of unknown kind " + std::to_string(op) + " (corrupt data)", at};
    }
  }
}

}  // namespace carenav::ros
