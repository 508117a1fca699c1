// What can be checked in the documentation is checked (issue 34): README.md, docs/*.md,
// cases/README.md and validation/**/README.md
//  - every relative link resolves (the file, and the heading of a #anchor in a Markdown file);
//  - every case key they name exists: the keys come from the case schema itself (case_keys of
//    every model with every setting that shows keys: rigid or sprung rings, several planes or
//    contact nodes, each loading), never from a hand list;
//  - every command-line option they name exists: the options of `rubdyn SUB` come from the CLI's
//    own --help (its option table); an option of one of the repository's scripts must be in
//    that script's source.
#include <catch2/catch.hpp>
#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "rubdyn/io/case_io.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "support/cli.hpp"

using namespace rubdyn;
using namespace rubdyn::testing;
namespace fs = std::filesystem;

namespace {

const fs::path kRoot = RUBDYN_SOURCE_DIR;

/// The documents checked.
std::vector<fs::path> documents() {
  std::vector<fs::path> docs = {kRoot / "README.md", kRoot / "cases" / "README.md"};
  for (const auto& e : fs::directory_iterator(kRoot / "docs"))
    if (e.path().extension() == ".md") docs.push_back(e.path());
  for (const auto& e : fs::recursive_directory_iterator(kRoot / "validation"))
    if (e.path().filename() == "README.md") docs.push_back(e.path());
  return docs;
}

/// A key with its plane or node number made K: plane.2.mu -> plane.K.mu.
std::string generic(const std::string& key) {
  static const std::regex numbered("^(plane|contact_node)\\.(\\d+|K|k)\\.");
  return std::regex_replace(key, numbered, "$1.K.");
}

/// Every key of every model with every setting that shows keys, as "section.key" (planes and
/// nodes as plane.K.key), from the case schema (case_keys).
std::set<std::string> schema_keys() {
  std::set<std::string> keys;
  const auto add = [&](CaseSpec c) {
    for (bool prescribed : {false, true})
      for (bool linear : {false, true}) {
        c.loads().spin = prescribed ? SpinDrive::Prescribed : SpinDrive::Torque;
        c.loads().torque_law = linear ? TorqueLaw::Linear : TorqueLaw::Constant;
        for (const std::string& k : case_keys(c)) keys.insert(generic(k));
      }
  };
  for (const auto& e : model_registry()) {
    for (bool rigid : {false, true}) {
      CaseSpec c;
      c.model = std::string(e.kind);
      c.jeffcott.stator.rigid = c.matrices.stator.rigid = rigid;
      add(c);
    }
  }
  // several planes and contact nodes, on sprung rings, and with a fixed ring
  for (bool fixed : {false, true}) {
    CaseSpec planes;
    planes.params.planes.assign(2, PlaneParams{});
    planes.params.planes[1].rigid = fixed;
    add(planes);
    CaseSpec nodes;
    nodes.model = "matrices";
    nodes.matrices.nodes.assign(2, MatrixNode{});
    nodes.matrices.nodes[1].stator.rigid = fixed;
    add(nodes);
  }
  return keys;
}

/// The sections of those keys.
std::set<std::string> sections_of(const std::set<std::string>& keys) {
  std::set<std::string> s;
  for (const auto& k : keys) s.insert(k.substr(0, k.find('.')));
  return s;
}

/// The options of a --help text (the CLI's option table: "  -h,--help ...", "  --out TEXT").
std::set<std::string> options_of_help(const std::string& help) {
  std::set<std::string> out;
  static const std::regex line("\\n\\s+(?:-\\w,)?(--[a-z][a-z0-9-]*)");
  for (auto it = std::sregex_iterator(help.begin(), help.end(), line); it != std::sregex_iterator();
       ++it)
    out.insert((*it)[1]);
  return out;
}

/// `rubdyn SUB`'s options, for every subcommand of `rubdyn --help`.
std::map<std::string, std::set<std::string>> cli_options() {
  std::map<std::string, std::set<std::string>> out;
  const CliOutcome top = cli("--help");
  REQUIRE(top.code == 0);
  const std::string subs = top.out.substr(top.out.find("Subcommands:"));
  static const std::regex sub("\\n  ([a-z][a-z-]*)  ");
  for (auto it = std::sregex_iterator(subs.begin(), subs.end(), sub); it != std::sregex_iterator();
       ++it) {
    const std::string name = (*it)[1];
    const CliOutcome h = cli(name + " --help");
    REQUIRE(h.code == 0);
    out[name] = options_of_help(h.out);
  }
  REQUIRE(out.count("run"));
  return out;
}

/// Text spans where keys and options are named: `inline code` and the lines of code blocks
/// (with the language of their block: a toml block is read as a case file).
struct Span {
  std::string text, lang;
  std::size_t offset;  ///< in the document (for its paragraph)
};
std::vector<Span> code_spans(const std::string& doc) {
  std::vector<Span> out;
  std::size_t i = 0;
  while (i < doc.size()) {
    if (doc.compare(i, 3, "```") == 0) {
      const std::size_t eol = doc.find('\n', i);
      const std::string lang = doc.substr(i + 3, eol - i - 3);
      const std::size_t end = doc.find("\n```", eol);
      std::size_t a = eol + 1;
      while (a < end) {
        const std::size_t b = std::min(doc.find('\n', a), end);
        out.push_back({doc.substr(a, b - a), lang, a});
        a = b + 1;
      }
      i = doc.find('\n', end + 1);
      if (i == std::string::npos) break;
      continue;
    }
    if (doc[i] == '`') {
      const std::size_t end = doc.find('`', i + 1);
      if (end == std::string::npos) break;
      const std::string span = doc.substr(i + 1, end - i - 1);
      if (span.find('\n') == std::string::npos) out.push_back({span, "", i});
      i = end + 1;
      continue;
    }
    ++i;
  }
  return out;
}

/// The paragraph of the document around `offset` (between blank lines).
std::string paragraph(const std::string& doc, std::size_t offset) {
  std::size_t a = doc.rfind("\n\n", offset), b = doc.find("\n\n", offset);
  a = a == std::string::npos ? 0 : a;
  return doc.substr(a, b == std::string::npos ? std::string::npos : b - a);
}

/// GitHub's anchor of a heading: lower case, punctuation dropped, spaces as hyphens.
std::string anchor_of(const std::string& heading) {
  std::string a;
  for (const char ch : heading) {
    const auto c = static_cast<unsigned char>(ch);
    if (std::isalnum(c) || ch == '-' || ch == '_')
      a += static_cast<char>(std::tolower(c));
    else if (ch == ' ')
      a += '-';
  }
  return a;
}

/// The source of a script a document names (relative to the repository or to the document's
/// folder; `-m rubdyn.plot` is python/rubdyn/plot.py), or "" when it names none.
std::string script_text(const std::string& word, const fs::path& doc_dir) {
  for (const fs::path& p : {kRoot / word, doc_dir / word})
    if (fs::is_regular_file(p)) return slurp(p);
  return "";
}

}  // namespace

TEST_CASE("Docs: every relative link resolves", "[docs]") {
  static const std::regex link("\\]\\(([^)\\s]+)\\)");
  static const std::regex heading("(^|\\n)#+ +([^\\n]+)");
  std::size_t checked = 0;
  for (const fs::path& doc : documents()) {
    const std::string text = slurp(doc);
    for (auto it = std::sregex_iterator(text.begin(), text.end(), link);
         it != std::sregex_iterator(); ++it) {
      const std::string target = (*it)[1];
      if (std::regex_search(target, std::regex("^(https?:|mailto:)"))) continue;
      const auto hash = target.find('#');
      const std::string file = target.substr(0, hash);
      const fs::path p = file.empty() ? doc : doc.parent_path() / file;
      INFO(doc.string() << ": " << target);
      CHECK(fs::exists(p));
      ++checked;
      if (hash == std::string::npos || !fs::is_regular_file(p) || p.extension() != ".md") continue;
      const std::string target_text = slurp(p);
      std::set<std::string> anchors;
      for (auto h = std::sregex_iterator(target_text.begin(), target_text.end(), heading);
           h != std::sregex_iterator(); ++h)
        anchors.insert(anchor_of((*h)[2]));
      CHECK(anchors.count(target.substr(hash + 1)) == 1);
    }
  }
  CHECK(checked > 20);  // (the documents link to each other and to the validation tables)
}

TEST_CASE("Docs: every case key they name exists", "[docs][io]") {
  const std::set<std::string> keys = schema_keys();
  const std::set<std::string> sections = sections_of(keys);
  std::string alternatives;
  for (const auto& s : sections) alternatives += (alternatives.empty() ? "" : "|") + s;
  // section.key not inside a longer name (a path, a file); the key may be a plane's K.key
  const std::regex named("(?:^|[^\\w./-])(" + alternatives +
                         ")\\.((?:\\d+\\.|K\\.)?[A-Za-z_]\\w*)(\\.\\w+)?");
  static const std::regex toml_section("^\\s*\\[\\[?([a-z_]+)\\]\\]?\\s*(#.*)?$");
  static const std::regex toml_key("^\\s*#?\\s*([a-z_][a-z0-9_]*)\\s*=");
  std::size_t checked = 0;
  for (const fs::path& doc : documents()) {
    const std::string text = slurp(doc);
    std::string toml_sec;
    for (const Span& sp : code_spans(text)) {
      std::smatch m;
      if (sp.lang == "toml") {  // a case file: [section] then key = value (or # key = value)
        if (std::regex_match(sp.text, m, toml_section)) {
          toml_sec = m[1];
        } else if (std::regex_search(sp.text, m, toml_key) && !toml_sec.empty()) {
          const std::string key = generic(toml_sec == "plane" || toml_sec == "contact_node"
                                              ? toml_sec + ".K." + std::string(m[1])
                                              : toml_sec + "." + std::string(m[1]));
          INFO(doc.string() << ": [" << toml_sec << "] " << sp.text);
          CHECK(keys.count(key) == 1);
          ++checked;
        }
        continue;
      }
      // in Python code, keys are the strings (case["contact.mu"]; `model.` is a variable)
      std::string where = sp.text;
      if (sp.lang == "python") {
        static const std::regex literal("\"([^\"]*)\"|'([^']*)'");
        where.clear();
        for (auto q = std::sregex_iterator(sp.text.begin(), sp.text.end(), literal);
             q != std::sregex_iterator(); ++q)
          where.append(" ").append((*q)[1].matched ? (*q)[1].str() : (*q)[2].str());
      }
      for (auto it = std::sregex_iterator(where.begin(), where.end(), named);
           it != std::sregex_iterator(); ++it) {
        const std::string sec = (*it)[1], key = (*it)[2], tail = (*it)[3];
        if (key == "K.key") continue;  // the pattern of a plane's keys (plane.K.key)
        // a file (loads.hpp, run.py, contact.png) or a Python module's attribute
        // (validation/siconos/model.py's model.law_check) is no key
        if (!tail.empty() || fs::exists(doc.parent_path() / (sec + ".py"))) continue;
        if (std::regex_match(key, std::regex("(hpp|cpp|py|png|md|csv|toml|json|sh|npy)"))) continue;
        const std::string full = generic(sec + "." + key);
        INFO(doc.string() << ": `" << sp.text << "`");
        CHECK(keys.count(full) == 1);
        ++checked;
      }
    }
  }
  CHECK(checked > 50);
}

TEST_CASE("Docs: every command-line option they name exists", "[docs][cli]") {
  const auto options = cli_options();
  std::set<std::string> any;
  for (const auto& [sub, opts] : options) any.insert(opts.begin(), opts.end());
  static const std::regex word("[^\\s\\[\\]|;&()]+");
  static const std::regex option("^(--[a-z][a-z0-9-]*)(=.*)?$");
  std::size_t checked = 0;
  for (const fs::path& doc : documents()) {
    const std::string text = slurp(doc);
    for (const Span& sp : code_spans(text)) {
      if (sp.lang == "toml") continue;
      const std::string line = sp.text.substr(0, sp.text.find(" #"));  // a comment ends it
      std::vector<std::string> words;
      for (auto it = std::sregex_iterator(line.begin(), line.end(), word);
           it != std::sregex_iterator(); ++it)
        words.push_back(it->str());
      // whose options: rubdyn SUB, a script of the repository, another program (not checked)
      enum class Owner { None, Rubdyn, Script, Other } owner = Owner::None;
      std::string sub, script;
      for (std::size_t i = 0; i < words.size(); ++i) {
        const std::string& w = words[i];
        std::smatch m;
        if (std::regex_match(w, m, option)) {
          const std::string opt = m[1];
          INFO(doc.string() << ": `" << sp.text << "`");
          if (owner == Owner::Rubdyn) {
            INFO("rubdyn " << sub);
            CHECK(options.at(sub).count(opt) == 1);
            ++checked;
          } else if (owner == Owner::Script) {
            INFO(script);
            CHECK(script.find(opt) != std::string::npos);
            ++checked;
          } else if (owner == Owner::None) {
            // an option named alone: of rubdyn, or of a script its paragraph names
            bool found = any.count(opt) == 1;
            const std::string par = paragraph(text, sp.offset);
            static const std::regex named_script("[\\w./-]+\\.(py|sh)");
            for (auto s = std::sregex_iterator(par.begin(), par.end(), named_script);
                 !found && s != std::sregex_iterator(); ++s)
              found = script_text(s->str(), doc.parent_path()).find(opt) != std::string::npos;
            CHECK(found);
            ++checked;
          }
          continue;
        }
        if ((w == "rubdyn" || w.ends_with("/rubdyn")) && i + 1 < words.size() &&
            options.count(words[i + 1])) {
          owner = Owner::Rubdyn;
          sub = words[++i];
        } else if (w == "-m" && i + 1 < words.size() && words[i + 1].starts_with("rubdyn.")) {
          owner = Owner::Script;
          script = slurp(kRoot / "python" / "rubdyn" / (words[++i].substr(7) + ".py"));
        } else if (w.ends_with(".py") || w.ends_with(".sh")) {
          script = script_text(w, doc.parent_path());
          owner = script.empty() ? Owner::Other : Owner::Script;
        } else if (owner == Owner::None && (w == "cmake" || w == "python3" || w == "pytest")) {
          owner = Owner::Other;
        }
      }
    }
  }
  CHECK(checked > 50);
}
