#include <carenav/common/errors.h>
#include <carenav/io/number_table.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

namespace carenav::io {

size_t readNumberRows(const std::string& path, int columns, const std::string& layout,
                      const std::function<void(const double* values, int line)>& row) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw InputError(path + ": is a directory");
  std::ifstream f(path);
  if (!f) throw InputError(path + ": cannot open it (no such file?)");
  std::vector<double> v(static_cast<size_t>(columns));
  std::string line;
  int lineno = 0;
  size_t rows = 0;
  while (std::getline(f, line)) {
    ++lineno;
    const auto b = line.find_first_not_of(" \t\r");
    if (b == std::string::npos || line[b] == '#') continue;
    std::istringstream is(line);
    int n = 0;
    while (n < columns && is >> v[n]) ++n;
    std::string extra;
    if (n != columns || (is >> extra))
      throw InputError(path + ":" + std::to_string(lineno) + ": expected " +
                       std::to_string(columns) + " numbers '" + layout + "', found " +
                       (n == columns ? std::string("more")
                                     : std::to_string(n) + " numbers" +
                                           (!is.eof() ? std::string(" and then text") : "")));
    for (double x : v)
      if (!std::isfinite(x))
        throw InputError(path + ":" + std::to_string(lineno) + ": not a finite number");
    row(v.data(), lineno);
    ++rows;
  }
  if (f.bad()) throw InputError(path + ": read error");
  return rows;
}

}  // namespace carenav::io
