// ncservo: the command-line face of the library. It parses arguments and presents; the protocol
// knowledge lives in the library's tables. Every subcommand (kSubcommands, each in a file of its
// own) and every output format (the format tables beside each subcommand, report.hpp's
// ReportFormat) is a row: the options, their choices and help, and the dispatch are derived from
// the rows.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "ncservo/base/text.hpp"

namespace {

using namespace ncservo;
using cli::Handler;
using cli::kExitOk;
using cli::kExitUsage;

// ninja's tool table: name, help, and the options' setup, which returns the handler.
struct Subcommand {
  const char* name;
  const char* help;
  Handler (*setup)(CLI::App& command);
};
const Subcommand kSubcommands[] = {
    {"decode", "print the decoded process data, one row per axis and cycle", cli::decodeCommand},
    {"validate", "check captures against the rules (docs/rules.md)", cli::validateCommand},
    {"diff",
     "compare two captures or JSON reports: findings, incidents, timing (docs/baselines.md)",
     cli::diffCommand},
    {"rules", "list the rules: ID, slug, severity, party, summary", cli::rulesCommand},
    {"fields", "list every decoded field (generated from the field table)", cli::fieldsCommand},
    {"simulate", "write a capture of simulated NC and drives (scenarios, faults)",
     cli::simulateCommand},
    {"annotate", "copy a capture with each finding as a packet comment on its frame",
     cli::annotateCommand},
    {"monitor", "capture live, report findings as they happen, keep a flight record",
     cli::monitorCommand},
    {"merge", "one report over many captures' JSON reports (docs/field.md)", cli::mergeCommand},
};

}  // namespace

// A first word that names no subcommand, with the closest one; "" when it names one or is an
// option (--help, --version).
std::string unknownCommandMessage(int argc, char** argv) {
  if (argc < 2 || argv[1][0] == '-') return "";
  const std::string word = argv[1];
  const std::vector<std::string> names = cli::namesOf(kSubcommands);
  if (std::find(names.begin(), names.end(), word) != names.end()) return "";
  return fmt::format("ncservo: unknown command '{}'{} (commands: {})", word,
                     didYouMean(word, names), cli::choiceList(names));
}

// The first --option of the subcommand's words that it does not take, with the closest one; ""
// when it takes them all.
std::string unknownOptionMessage(const CLI::App& app, int argc, char** argv) {
  if (argc < 2 || argv[1][0] == '-') return "";
  const CLI::App* command = app.get_subcommand(argv[1]);
  std::vector<std::string> options;
  for (const CLI::Option* option : command->get_options()) {
    for (const std::string& name : option->get_lnames()) options.push_back("--" + name);
  }
  for (int i = 2; i < argc; ++i) {
    const std::string word = argv[i];
    if (word == "--") break;
    if (word.rfind("--", 0) != 0) continue;
    const std::string name = word.substr(0, word.find('='));
    if (std::find(options.begin(), options.end(), name) != options.end()) continue;
    return fmt::format("ncservo {}: unknown option '{}'{}", argv[1], name,
                       didYouMean(name, options));
  }
  return "";
}

int main(int argc, char** argv) {
  CLI::App app{"ncservo: decode and check NC <-> servo EtherCAT process data"};
  const std::string version = std::string("ncservo ") + NCSERVO_VERSION;
  app.set_version_flag("--version", version);
  app.require_subcommand(1);
  std::vector<std::pair<CLI::App*, Handler>> commands;
  for (const Subcommand& s : kSubcommands) {
    CLI::App* command = app.add_subcommand(s.name, s.help);
    command->set_version_flag("--version", version);
    commands.emplace_back(command, s.setup(*command));
  }
  if (const std::string unknown = unknownCommandMessage(argc, argv); !unknown.empty()) {
    fmt::print(stderr, "{}\n", unknown);
    return kExitUsage;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (app.exit(e) == 0) return kExitOk;
    if (const std::string unknown = unknownOptionMessage(app, argc, argv); !unknown.empty()) {
      fmt::print(stderr, "{}\n", unknown);
    }
    return kExitUsage;
  }
  for (const auto& [command, handler] : commands) {
    if (command->parsed()) return handler();
  }
  return kExitUsage;
}
