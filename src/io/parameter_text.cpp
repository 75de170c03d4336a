// The schema written out (parameters.hpp): the scene as TOML for --dry-run,
// and the configuration reference as markdown for docs/configuration.md.
#include <algorithm>
#include <sstream>

#include "io/parameters.hpp"

namespace drape {
namespace {

// The keys of one section ("" for the top level), in declaration order.
std::vector<const Parameter*> in_section(const ParameterList& list, const std::string& section) {
  std::vector<const Parameter*> v;
  for (const Parameter& p : list.all())
    if (p.section == section) v.push_back(&p);
  return v;
}

// "key = value  # comment", comments aligned for reading.
void toml_line(std::ostringstream& os, const Parameter& p, const Scene& s) {
  std::string kv = p.key + " = " + value_text(p.get(s));
  if (!p.comment.empty()) kv.resize(std::max<size_t>(kv.size() + 1, 34), ' '), kv += "# " + p.comment;
  os << kv << "\n";
}

// Markdown's table cells: a '|' would end the cell.
std::string cell(const std::string& text) {
  std::string s;
  for (char c : text) s += c == '|' ? std::string("\\|") : std::string(1, c);
  return s;
}

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size()))
    s.replace(at, from.size(), to);
  return s;
}

// The allowed values as the reference shows them: `box`, `sphere`; each ≥ 3.
std::string allowed(const Parameter& p) {
  std::string s;
  for (const std::string& c : p.choices) s += (s.empty() ? "`" : ", `") + c + "`";
  if (!s.empty() || p.bound.text.empty()) return s;
  s = (p.bound.subject.empty() ? "" : "each ") + p.bound.text;
  if (!p.bound.note.empty()) s += " (" + p.bound.note + ")";
  return replace_all(replace_all(s, ">=", "≥"), "<=", "≤");
}

void markdown_table(std::ostringstream& os, const std::vector<const Parameter*>& params, const Scene& defaults) {
  os << "| key | default | unit | allowed | meaning |\n|---|---|---|---|---|\n";
  for (const Parameter* p : params)
    os << "| `" << p->full_name() << "` | `" << value_text(p->get(defaults)) << "` | " << cell(p->unit) << " | "
       << cell(allowed(*p)) << " | " << cell(p->doc) << " |\n";
}

}  // namespace

std::string parameters_to_toml(const ParameterList& list, const Scene& s) {
  std::ostringstream os;
  os << "# drape scene, fully resolved (SI units)\n";
  for (const Parameter* p : in_section(list, "")) toml_line(os, *p, s);
  for (const std::string& section : list.sections()) {
    os << "\n[" << section << "]\n";
    for (const Parameter* p : in_section(list, section)) toml_line(os, *p, s);
  }
  return os.str();
}

std::string parameters_to_markdown(const ParameterList& list, const Scene& defaults) {
  std::ostringstream os;
  os << "## Top level\n\n";
  markdown_table(os, in_section(list, ""), defaults);
  for (const std::string& section : list.sections()) {
    os << "\n## `[" << section << "]`\n\n";
    markdown_table(os, in_section(list, section), defaults);
  }
  return os.str();
}

}  // namespace drape
