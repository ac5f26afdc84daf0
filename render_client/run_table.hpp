// The short table a person reads at the end of a run (the cluster's and the reference's), printed
// before the key=value `summary:` line that scripts read. Plain text: a title, then one row a
// measure, the labels in one column; time rows give a median and a p99 in aligned columns, the
// other rows one line of text.
#pragma once
#include <cstdio>
#include <string>
#include <vector>

namespace occ {

// The median and the 99th percentile of `values` as the summary line takes them: the sorted
// values at index n / 2 and min(n - 1, n * 99 / 100). Both 0 for no values.
struct Spread {
  double median = 0, p99 = 0;
};
Spread spread(std::vector<double> values);

class RunTable {
 public:
  explicit RunTable(std::string title) : title_(std::move(title)) {}
  // A row of the median and the p99 of `values` (spread()), under the columns "median" and
  // "p99"; no values: "-" in both.
  void times(const std::string& label, const std::vector<double>& values);
  // A row of free text.
  void text(const std::string& label, const std::string& value);
  // The title, the column heads (when there are time rows) and the rows, then a flush: the table
  // stays one block in a log that stderr shares.
  void print(std::FILE* out) const;

 private:
  struct Row {
    std::string label;
    std::vector<std::string> cells;  // time rows: median, p99; text rows: one cell
    bool numbers = false;
  };
  std::string title_;
  std::vector<Row> rows_;
};

// printf into a std::string.
std::string format(const char* fmt, ...) __attribute__((format(printf, 1, 2)));

}  // namespace occ
