#include <carenav/common/errors.h>
#include <carenav/slam/mapper.h>

#include <map>
#include <mutex>

namespace carenav::slam {

namespace {
std::map<std::string, MapperFactory>& registry() {
  static std::map<std::string, MapperFactory> r;
  static std::once_flag once;
  std::call_once(once, [] {
    r["icp"] = makeIcpMapper;
    r["icp-graph"] = makeIcpGraphMapper;
    r["rbpf"] = makeRbpfMapper;
  });
  return r;
}
}  // namespace

void registerMapper(const std::string& name, MapperFactory f) { registry()[name] = std::move(f); }

std::vector<std::string> mapperNames() {
  std::vector<std::string> out;
  for (const auto& [k, v] : registry()) out.push_back(k);
  return out;
}

std::unique_ptr<Mapper> createMapper(const std::string& name, const MapperConfig& cfg) {
  auto it = registry().find(name);
  if (it == registry().end()) {
    std::string known;
    for (const auto& n : mapperNames()) known += (known.empty() ? "" : ", ") + n;
    throw InputError("unknown SLAM method '" + name + "' (known: " + known + ")");
  }
  return it->second(cfg);
}

mrpt::obs::CObservation2DRangeScan::Ptr clipScan(const mrpt::obs::CObservation2DRangeScan::Ptr& s,
                                                 double range_max) {
  if (range_max <= 0 || s->maxRange <= range_max) return s;
  auto c = std::make_shared<mrpt::obs::CObservation2DRangeScan>(*s);
  for (size_t i = 0; i < c->getScanSize(); ++i)
    if (c->getScanRange(i) > range_max) c->setScanRangeValidity(i, false);
  c->maxRange = static_cast<float>(range_max);
  return c;
}

}  // namespace carenav::slam
