// `ncservo fields` (docs/fields.md is its markdown): the field table as text.
// Not fields.cpp: include_cycles.py takes a header and a source of one name for one module.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "ncservo/pipeline/expert_notes.hpp"
#include "ncservo/protocol/fields.hpp"
#include "ncservo/rules/rules.hpp"

namespace ncservo::cli {

using namespace report;  // the report layer's names
namespace {

std::string maskText(const FieldDef& f) {
  return f.mask ? fmt::format("0x{:X}", f.mask) : "all";
}

void printFieldTsv(const FieldDef& f) {
  fmt::print("{}\t{}\t{}\t{}\t{}\n", f.filter, f.label, wordDef(f.word).name, maskText(f), f.blurb);
}

void printDerivedTsv(const DerivedFieldDef& f) {
  fmt::print("{}\t{}\t(derived)\t\t{}\n", f.filter, f.label, f.blurb);
}

void printFieldMarkdown(const FieldDef& f) {
  std::string values;
  for (std::size_t i = 0; i < f.value_count; ++i) {
    values += fmt::format("{}{}={}{}", i ? "; " : "", f.values[i].value, f.values[i].name,
                          f.values[i].unit ? fmt::format(" [{}]", f.values[i].unit) : "");
  }
  fmt::print("| `{}` | {} | {} | {} | {} | {} | {} | {} |\n", f.filter, f.label,
             wordDef(f.word).name, maskText(f), values,
             f.at_rest ? fmt::format("{}", *f.at_rest) : "", f.blurb, f.clause);
}

void printDerivedMarkdown(const DerivedFieldDef& f) {
  fmt::print("| `{}` | {} | (derived) | | | | {} | docs/plugin.md |\n", f.filter, f.label, f.blurb);
}

// An expert item of the plugin's: one per rule (its filter from the rule table), then the notes.
struct ExpertRow {
  std::string filter;
  std::string label;
  const char* level;
  std::string meaning;
  const char* spec;
};

std::vector<ExpertRow> expertRows() {
  constexpr const char* kLevels[] = {"chat", "note", "warning", "error"};
  std::vector<ExpertRow> rows;
  for (const RuleDef& rule : kRules) {
    rows.push_back({ruleFilterName(rule), fmt::format("{} {}", rule.code, rule.slug),
                    severityName(rule.severity), rule.summary, "docs/rules.md"});
  }
  for (const ExpertNoteDef& note : kExpertNotes) {
    rows.push_back({note.filter, note.summary, kLevels[static_cast<std::size_t>(note.level)],
                    note.summary, "docs/plugin.md"});
  }
  return rows;
}

void printExpertTsv(const ExpertRow& e) {
  fmt::print("{}\t{}\t(expert, {})\t\t{}\n", e.filter, e.label, e.level, e.meaning);
}

void printExpertMarkdown(const ExpertRow& e) {
  fmt::print("| `{}` | {} | (expert, {}) | | | | {} | {} |\n", e.filter, e.label, e.level,
             e.meaning, e.spec);
}

// `fields`'s formats: a header, then one line per field of the field table, per derived field,
// then per expert item: every field the plugin registers (fields_registered.sh).
struct FieldListFormat {
  const char* name;
  const char* header;
  void (*field)(const FieldDef& f);
  void (*derived)(const DerivedFieldDef& f);
  void (*expert)(const ExpertRow& e);
};
const FieldListFormat kFieldListFormats[] = {
    {.name = "tsv",
     .header = "",
     .field = printFieldTsv,
     .derived = printDerivedTsv,
     .expert = printExpertTsv},
    {.name = "markdown",
     .header = "| filter name | label | word | bits | values | at rest | meaning | spec |\n"
               "|---|---|---|---|---|---|---|---|\n",
     .field = printFieldMarkdown,
     .derived = printDerivedMarkdown,
     .expert = printExpertMarkdown},
};

}  // namespace

Handler fieldsCommand(CLI::App& command) {
  auto format = std::make_shared<std::string>(kFieldListFormats[0].name);
  addFormatOption(command, *format, namesOf(kFieldListFormats));
  return [format] {
    const FieldListFormat& list = rowNamed(kFieldListFormats, *format);
    fmt::print("{}", list.header);
    for (const FieldDef& f : kFields) list.field(f);
    for (const DerivedFieldDef& f : kDerivedFields) list.derived(f);
    for (const ExpertRow& e : expertRows()) list.expert(e);
    return kExitOk;
  };
}

}  // namespace ncservo::cli
