// Small HTML building blocks for the report: escaping, fixed-point numbers and tables.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace scanreg::report {

std::string Escape(std::string_view text);  // & < > " '
std::string Fixed(double value, int decimals);

// <table id=...> with a header row and one <tr> per AddRow in <tbody>. Cells are HTML (escape
// text with Escape()).
class HtmlTable {
 public:
  HtmlTable(std::string id, std::vector<std::string> header);
  void AddRow(const std::vector<std::string>& cells, const std::string& row_class = "");
  std::size_t rows() const { return rows_; }
  std::string Html() const;

 private:
  std::string id_;
  std::vector<std::string> header_;
  std::string body_;
  std::size_t rows_ = 0;
};

}  // namespace scanreg::report
