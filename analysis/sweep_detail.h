// hsnc -- what the sweep's distribution shares (private to the library):
// the text form of tasks' points that MPI ranks send to rank 0 and part
// files hold. Numbers are written with 17 significant digits, so they read
// back to the same doubles.
#pragma once

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "hsnc/sweep.h"

namespace hsnc::sweep_detail {

/// "task INDEX POINTS" then one line per point, for each task of `which`.
std::string write_tasks(const std::vector<std::size_t>& which, const std::vector<std::vector<SweepPoint>>& points,
                        std::size_t masses);

/// Reads what write_tasks wrote into `out` (task index -> points), starting
/// at line `first` of `lines`. Throws InputError "WHERE:LINE: ..." when damaged
/// or when a task is already in `out`.
void read_tasks(const std::vector<std::string>& lines, std::size_t first, std::size_t masses,
                const std::string& where, std::map<std::size_t, std::vector<SweepPoint>>& out);

std::vector<std::string> split_lines(const std::string& text);

}  // namespace hsnc::sweep_detail
