// mesopen: mesoscale simulation of projectiles penetrating granular targets.
#include "command_log.hpp"
#include "commands.hpp"
#include "scene.hpp"
#include "version.hpp"

#include <CLI/CLI.hpp>

#include <iostream>

namespace {

// An output directory's name: not empty.
const CLI::Validator output_directory(
    [](const std::string &dir) {
      return dir.empty() ? std::string("an empty name; allowed: a directory's path")
                         : std::string();
    },
    "DIR");

// A seed: a whole number in target.seed's range, checked before CLI11 reads it as unsigned (which
// wraps -1 around).
const CLI::Validator seed_range(
    [](const std::string &text) {
      const std::string allowed = "allowed: a whole number from 0 to 9e15 (target.seed's range)";
      if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos ||
          text.size() > 16 || std::stod(text) > 9.0e15)
        return "'" + text + "': " + allowed;
      return std::string();
    },
    "SEED");

// A subcommand that reads a scene and writes into a directory (`required`: both must be given;
// else the command checks them).
CLI::App *sceneCommand(CLI::App &app, const char *name, const char *about,
                       mesopen::SceneOptions &options, bool required = true) {
  auto *cmd = app.add_subcommand(name, about);
  cmd->add_option("scene", options.scene, "scene file (TOML)")->required(required);
  cmd->add_option("-o,--output", options.out_dir, "output directory")
      ->required(required)
      ->check(output_directory);
  cmd->add_option("--seed", options.seed, "random seed of the target (overrides target.seed)")
      ->check(seed_range);
  cmd->add_option("--threads", options.threads, "threads (default: all cores)")
      ->check(CLI::Range(1, 1024));
  return cmd;
}

} // namespace

int main(int argc, char **argv) {
  CLI::App app{"mesopen: 2D mesoscale simulation of projectiles penetrating dry sand"};
  app.set_version_flag("--version", std::string("mesopen ") + mesopen::programVersion());
  app.require_subcommand(1);

  mesopen::TargetOptions target;
  auto *cmd =
      sceneCommand(app, "target", "make a sand target and the projectile from a scene", target);
  cmd->add_flag("--no-mesh", target.no_mesh, "grains as polygons only, no triangles");
  cmd->add_flag("--no-plot", target.no_plot, "no grain-size histogram PNG");

  mesopen::RunOptions run;
  auto *run_cmd = sceneCommand(
      app, "run", "run a scene: the projectile and the grains as finite elements", run, false);
  run_cmd->add_flag("--quiet", run.quiet, "no progress line");
  run_cmd
      ->add_option("--resume", run.resume,
                   "continue the run in this output directory from its last checkpoint (instead "
                   "of SCENE -o DIR)")
      ->check(output_directory);

  mesopen::AnalyzeOptions analyze;
  auto *analyze_cmd = app.add_subcommand(
      "analyze", "measures of instability from runs' run.h5: instability.json in each, plots of "
                 "every run overlaid");
  analyze_cmd->add_option("dirs", analyze.dirs, "run directories (each with run.h5)")->required();
  analyze_cmd
      ->add_option("-o,--output", analyze.out_dir,
                   "directory for the plots (default: the first run's)")
      ->check(output_directory);
  analyze_cmd->add_flag("--no-plot", analyze.no_plot, "no PNG plots");

  mesopen::ModalOptions modal;
  auto *modal_cmd = app.add_subcommand(
      "modal", "free vibration modes of the projectile or a beam (scene's [modal] table), or of "
               "the projectile's mesh in target.h5 or run.h5");
  modal_cmd->add_option("input", modal.input, "scene (.toml), target.h5 or run.h5")->required();
  modal_cmd->add_option("-o,--output", modal.out_dir, "output directory")
      ->required()
      ->check(output_directory);
  modal_cmd->add_option("--modes", modal.modes, "elastic modes wanted (overrides modal.modes)")
      ->check(CLI::Range(1, 200));
  modal_cmd->add_option("--threads", modal.threads, "threads (default: all cores)")
      ->check(CLI::Range(1, 1024));

  mesopen::CampaignOptions campaign;
  auto *campaign_cmd = app.add_subcommand(
      "campaign", "run every scene of a campaign on its replicates (resumable), tabulate the "
                  "measures of instability with 95 % intervals, test its trends, plot");
  campaign_cmd->add_option("campaign", campaign.campaign, "campaign file (TOML)")->required();
  campaign_cmd->add_option("-o,--output", campaign.out_dir, "output directory")
      ->required()
      ->check(output_directory);
  campaign_cmd
      ->add_option("--replicates", campaign.replicates,
                   "target layouts per run (overrides campaign.replicates)")
      ->check(CLI::Range(1, 1000));
  campaign_cmd->add_option("--representation", campaign.representation,
                           "fe, dem or hybrid for every run (overrides campaign.representation)");
  campaign_cmd->add_option("--only", campaign.only, "run only these runs (names)")->delimiter(',');
  campaign_cmd
      ->add_option("--threads", campaign.threads, "threads of each run (default: all cores)")
      ->check(CLI::Range(1, 1024));
  campaign_cmd->add_flag("--quiet", campaign.quiet, "no progress line");

  auto *keys =
      app.add_subcommand("keys", "print every scene key with its default and allowed range");

  // A first word that names no command is said with the command names (CLI11 says only that a
  // subcommand is required).
  if (argc > 1) {
    const std::string first = argv[1];
    std::string names;
    bool known = first == "-h" || first == "--help" || first == "--version";
    const CLI::App &commands = app;
    for (const CLI::App *sub : commands.get_subcommands({})) {
      known = known || sub->check_name(first);
      names += names.empty() ? sub->get_name() : ", " + sub->get_name();
    }
    if (!known) {
      std::cerr << "mesopen: unknown " << (first.starts_with('-') ? "option" : "command") << " '"
                << first
                << "'; allowed: " << (first.starts_with('-') ? "--help, --version, or " : "")
                << names << "\nRun with --help for more information.\n";
      return 2;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError &e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  run.command_line = target.command_line = modal.command_line = mesopen::shellWords(argc, argv);
  if (*keys) {
    std::cout << mesopen::sceneKeysMarkdown();
    return 0;
  }
  if (*run_cmd)
    return mesopen::runCommand(run);
  if (*analyze_cmd)
    return mesopen::analyzeCommand(analyze);
  if (*campaign_cmd)
    return mesopen::campaignCommand(campaign);
  if (*modal_cmd)
    return mesopen::modalCommand(modal);
  return mesopen::targetCommand(target);
}
