#include "render_client/run_table.hpp"

#include <algorithm>
#include <cstdarg>

namespace occ {

Spread spread(std::vector<double> values) {
  if (values.empty()) return {};
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return {values[n / 2], values[std::min(n - 1, n * 99 / 100)]};
}

std::string format(const char* fmt, ...) {
  char text[512];
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(text, sizeof text, fmt, args);
  va_end(args);
  return text;
}

void RunTable::times(const std::string& label, const std::vector<double>& values) {
  if (values.empty()) {
    rows_.push_back({label, {"-", "-"}, true});
    return;
  }
  const Spread s = spread(values);
  rows_.push_back({label, {format("%.2f", s.median), format("%.2f", s.p99)}, true});
}

void RunTable::text(const std::string& label, const std::string& value) { rows_.push_back({label, {value}, false}); }

void RunTable::print(std::FILE* out) const {
  size_t label_w = 0, cell_w[2] = {std::string("median").size(), std::string("p99").size()};
  bool any_numbers = false;
  for (const Row& r : rows_) {
    label_w = std::max(label_w, r.label.size());
    if (!r.numbers) continue;
    any_numbers = true;
    for (size_t c = 0; c < 2; ++c) cell_w[c] = std::max(cell_w[c], r.cells[c].size());
  }
  std::fflush(out);
  std::fprintf(out, "%s\n", title_.c_str());
  if (any_numbers)
    std::fprintf(out, "  %-*s  %*s  %*s\n", int(label_w), "", int(cell_w[0]), "median", int(cell_w[1]), "p99");
  for (const Row& r : rows_) {
    if (r.numbers)
      std::fprintf(out, "  %-*s  %*s  %*s\n", int(label_w), r.label.c_str(), int(cell_w[0]), r.cells[0].c_str(),
                   int(cell_w[1]), r.cells[1].c_str());
    else
      std::fprintf(out, "  %-*s  %s\n", int(label_w), r.label.c_str(), r.cells[0].c_str());
  }
  std::fflush(out);
}

}  // namespace occ
