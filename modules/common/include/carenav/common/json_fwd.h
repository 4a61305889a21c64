// The JSON value type, declared only (for headers that name it); the
// definition and the helpers are in json.h.
#pragma once

#include <nlohmann/json_fwd.hpp>

namespace carenav {

/** A JSON value whose objects keep their keys in insertion order (summaries
 *  read top-down in the order they were written). */
using Json = nlohmann::ordered_json;

}  // namespace carenav
