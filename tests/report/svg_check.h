#pragma once

// A small XML well-formedness check for the report's SVG files, and a measure of how much data
// a figure draws (vertices of its paths, points of its polylines).

#include <algorithm>
#include <cctype>
#include <string>
#include <vector>

namespace rotorid::testing {

struct SvgCheck {
  bool well_formed = false;
  std::string error;  // first problem found
  std::string root;   // name of the root element
  int elements = 0;
  int paths = 0;
  int max_path_vertices = 0;  // largest single <path>/<polyline>: a data curve, not an axis tick
  int total_vertices = 0;
};

inline SvgCheck CheckSvg(const std::string& text) {
  SvgCheck out;
  std::vector<std::string> open;
  size_t pos = 0;
  bool root_closed = false;
  auto fail = [&](const std::string& why) {
    out.well_formed = false;
    out.error = why + " at byte " + std::to_string(pos);
    return out;
  };
  auto is_name_char = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == ':' || c == '_' || c == '-' || c == '.';
  };
  while (pos < text.size()) {
    const size_t lt = text.find('<', pos);
    if (lt == std::string::npos) break;
    if (root_closed && text.find_first_not_of(" \t\r\n", pos) < lt) return fail("text after the root element");
    pos = lt;
    if (text.compare(pos, 4, "<!--") == 0) {
      const size_t end = text.find("-->", pos);
      if (end == std::string::npos) return fail("unterminated comment");
      pos = end + 3;
      continue;
    }
    if (text.compare(pos, 9, "<![CDATA[") == 0) {
      const size_t end = text.find("]]>", pos);
      if (end == std::string::npos || open.empty()) return fail("bad CDATA");
      pos = end + 3;
      continue;
    }
    if (text.compare(pos, 2, "<?") == 0) {
      const size_t end = text.find("?>", pos);
      if (end == std::string::npos) return fail("unterminated processing instruction");
      pos = end + 2;
      continue;
    }
    if (text.compare(pos, 2, "<!") == 0) {  // DOCTYPE, possibly with an internal subset
      const size_t bracket = text.find('[', pos), gt = text.find('>', pos);
      size_t end = gt;
      if (bracket != std::string::npos && bracket < gt) end = text.find("]>", bracket) + 1;
      if (end == std::string::npos || end == 0) return fail("unterminated declaration");
      pos = end + 1;
      continue;
    }
    const bool closing = text.compare(pos, 2, "</") == 0;
    size_t p = pos + (closing ? 2 : 1);
    const size_t name_start = p;
    while (p < text.size() && is_name_char(text[p])) ++p;
    const std::string name = text.substr(name_start, p - name_start);
    if (name.empty()) return fail("tag without a name");
    if (closing) {
      while (p < text.size() && std::isspace(static_cast<unsigned char>(text[p]))) ++p;
      if (p >= text.size() || text[p] != '>') return fail("malformed closing tag </" + name);
      if (open.empty() || open.back() != name)
        return fail("</" + name + "> closes <" + (open.empty() ? std::string("nothing") : open.back()) + ">");
      open.pop_back();
      if (open.empty()) root_closed = true;
      pos = p + 1;
      continue;
    }
    if (root_closed) return fail("second root element <" + name + ">");
    // Attributes: name = "value" | 'value', each name once.
    std::vector<std::string> attribute_names;
    std::string d_attribute, points_attribute;
    bool self_closing = false;
    for (;;) {
      while (p < text.size() && std::isspace(static_cast<unsigned char>(text[p]))) ++p;
      if (p >= text.size()) return fail("unterminated tag <" + name);
      if (text[p] == '>') break;
      if (text.compare(p, 2, "/>") == 0) {
        self_closing = true;
        ++p;
        break;
      }
      const size_t attr_start = p;
      while (p < text.size() && is_name_char(text[p])) ++p;
      const std::string attr = text.substr(attr_start, p - attr_start);
      if (attr.empty()) return fail("bad attribute in <" + name);
      while (p < text.size() && std::isspace(static_cast<unsigned char>(text[p]))) ++p;
      if (p >= text.size() || text[p] != '=') return fail("attribute " + attr + " without value in <" + name);
      ++p;
      while (p < text.size() && std::isspace(static_cast<unsigned char>(text[p]))) ++p;
      if (p >= text.size() || (text[p] != '"' && text[p] != '\'')) return fail("unquoted attribute " + attr);
      const char quote = text[p];
      const size_t value_end = text.find(quote, p + 1);
      if (value_end == std::string::npos) return fail("unterminated attribute " + attr);
      const std::string value = text.substr(p + 1, value_end - p - 1);
      if (value.find('<') != std::string::npos) return fail("'<' in attribute " + attr);
      if (std::find(attribute_names.begin(), attribute_names.end(), attr) != attribute_names.end())
        return fail("duplicate attribute " + attr + " in <" + name);
      attribute_names.push_back(attr);
      if (attr == "d") d_attribute = value;
      if (attr == "points") points_attribute = value;
      p = value_end + 1;
    }
    if (out.root.empty()) out.root = name;
    ++out.elements;
    if (name == "path" || name == "polyline") {
      ++out.paths;
      // gnuplot writes every vertex as "x,y"; polylines likewise.
      const std::string& coords = name == "path" ? d_attribute : points_attribute;
      const int vertices = static_cast<int>(std::count(coords.begin(), coords.end(), ','));
      out.total_vertices += vertices;
      out.max_path_vertices = std::max(out.max_path_vertices, vertices);
    }
    if (!self_closing) open.push_back(name);
    pos = p + 1;
  }
  if (!open.empty()) return fail("<" + open.back() + "> never closed");
  if (out.root.empty()) return fail("no element");
  out.well_formed = true;
  return out;
}

}  // namespace rotorid::testing
