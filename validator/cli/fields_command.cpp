// `ncservo fields` (docs/fields.md is its markdown): the field table as text.
// Not fields.cpp: include_cycles.py takes a header and a source of one name for one module.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "commands.hpp"
#include "ncservo/protocol/fields.hpp"

namespace ncservo::cli {
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
  fmt::print("| `{}` | {} | {} | {} | {} | {} | {} |\n", f.filter, f.label, wordDef(f.word).name,
             maskText(f), values, f.blurb, f.clause);
}

void printDerivedMarkdown(const DerivedFieldDef& f) {
  fmt::print("| `{}` | {} | (derived) | | | {} | docs/plugin.md |\n", f.filter, f.label, f.blurb);
}

// `fields`'s formats: a header, then one line per field of the field table, then per derived field.
struct FieldListFormat {
  const char* name;
  const char* header;
  void (*field)(const FieldDef& f);
  void (*derived)(const DerivedFieldDef& f);
};
const FieldListFormat kFieldListFormats[] = {
    {.name = "tsv", .header = "", .field = printFieldTsv, .derived = printDerivedTsv},
    {.name = "markdown",
     .header = "| filter name | label | word | bits | values | meaning | spec |\n"
               "|---|---|---|---|---|---|---|\n",
     .field = printFieldMarkdown,
     .derived = printDerivedMarkdown},
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
    return kExitOk;
  };
}

}  // namespace ncservo::cli
