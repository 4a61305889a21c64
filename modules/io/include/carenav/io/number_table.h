// Text files of fixed-width number rows (TUM trajectories, relations files):
// one reader, so every such format gives the same errors for the same faults.
#pragma once

#include <functional>
#include <string>

namespace carenav::io {

/** Calls `row(values, line)` for every data line of `path`: `columns`
 *  finite numbers separated by white space. Blank lines and lines starting
 *  with '#' are skipped. Throws InputError naming the file (and line) for a
 *  missing file, a directory, a read error, or a line with another count of
 *  numbers or a non-finite one; `layout` (e.g. "t x y z qx qy qz qw") is
 *  quoted in that message. Returns the number of rows. */
size_t readNumberRows(const std::string& path, int columns, const std::string& layout,
                      const std::function<void(const double* values, int line)>& row);

}  // namespace carenav::io
