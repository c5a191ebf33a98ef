#include "core/report/html_table.h"

#include <cstdio>

namespace scanreg::report {

std::string Escape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string Fixed(double value, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
  std::string text = buf;
  // "-0.0": a tiny negative residual reads as a sign that is not there.
  if (text[0] == '-' && text.find_first_not_of("-0.") == std::string::npos) text.erase(0, 1);
  return text;
}

HtmlTable::HtmlTable(std::string id, std::vector<std::string> header)
    : id_(std::move(id)), header_(std::move(header)) {}

void HtmlTable::AddRow(const std::vector<std::string>& cells, const std::string& row_class) {
  body_ += row_class.empty() ? "<tr>" : "<tr class=\"" + row_class + "\">";
  for (const std::string& c : cells) body_ += "<td>" + c + "</td>";
  body_ += "</tr>\n";
  ++rows_;
}

std::string HtmlTable::Html() const {
  std::string html = "<table id=\"" + id_ + "\">\n<thead><tr>";
  for (const std::string& h : header_) html += "<th>" + h + "</th>";
  return html + "</tr></thead>\n<tbody>\n" + body_ + "</tbody>\n</table>\n";
}

}  // namespace scanreg::report
