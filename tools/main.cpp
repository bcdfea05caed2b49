// mesopen: mesoscale simulation of projectiles penetrating granular targets.
#include "commands.hpp"
#include "scene.hpp"

#include <CLI/CLI.hpp>

#include <iostream>

int main(int argc, char **argv) {
  CLI::App app{"mesopen: 2D mesoscale simulation of projectiles penetrating dry sand"};
  app.require_subcommand(1);

  mesopen::TargetOptions target;
  auto *cmd = app.add_subcommand("target", "make a sand target and the projectile from a scene");
  cmd->add_option("scene", target.scene, "scene file (TOML)")->required();
  cmd->add_option("-o,--output", target.out_dir, "output directory")->required();
  cmd->add_option("--seed", target.seed, "random seed (overrides target.seed)");
  cmd->add_option("--threads", target.threads, "threads (default: all cores)")->check(CLI::Range(1, 1024));
  cmd->add_flag("--no-mesh", target.no_mesh, "grains as polygons only, no triangles");
  cmd->add_flag("--no-plot", target.no_plot, "no grain-size histogram PNG");

  mesopen::RunOptions run;
  auto *run_cmd = app.add_subcommand("run", "run a scene: the projectile and the grains as finite elements");
  run_cmd->add_option("scene", run.scene, "scene file (TOML)")->required();
  run_cmd->add_option("-o,--output", run.out_dir, "output directory")->required();
  run_cmd->add_option("--seed", run.seed, "random seed of the target (overrides target.seed)");
  run_cmd->add_option("--threads", run.threads, "threads (default: all cores)")->check(CLI::Range(1, 1024));
  run_cmd->add_flag("--quiet", run.quiet, "no progress line");

  auto *keys = app.add_subcommand("keys", "print every scene key with its default and allowed range");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError &e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  if (*keys) {
    std::cout << mesopen::sceneKeysMarkdown();
    return 0;
  }
  if (*run_cmd)
    return mesopen::runCommand(run);
  return mesopen::targetCommand(target);
}
