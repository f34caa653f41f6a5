// The table of marches (glint/marches.h).
#include "glint/marches.h"

#include <string>

#include "glint/errors.h"

namespace glint {

const std::vector<MarchInfo>& march_table() {
  static const std::vector<MarchInfo> table = [] {
    std::vector<MarchInfo> rows = registered_marches();
    for (size_t k = 0; k < rows.size(); ++k) rows[k].id = static_cast<March>(k);
    return rows;
  }();
  return table;
}

const MarchInfo& march_info(March m) {
  for (const MarchInfo& info : march_table())
    if (info.id == m) return info;
  throw Error("glint: march " + std::to_string(static_cast<int>(m)) + " is not in the table");
}

std::string march_names(const char* sep) {
  std::string names;
  for (const MarchInfo& info : march_table()) {
    if (!names.empty()) names += sep;
    names += info.name;
  }
  return names;
}

const MarchInfo& march_info(const std::string& name) {
  for (const MarchInfo& info : march_table())
    if (name == info.name) return info;
  throw InvalidArgument("march", "expected one of " + march_names() + ", got \"" + name + "\"");
}

}  // namespace glint
