// The one wiring point: builds the command tree and maps failures to exit
// codes (0 success, 1 run-time failure, 2 bad arguments or input).
#include "common.hpp"
#include "lsl_args.hpp"

#include "curvlab/harness/version.hpp"

#include <CLI/CLI.hpp>

#include <iostream>

int main(int argc, char** argv) {
  curvlab::harness::cli::ignore_broken_pipes();
  CLI::App app{"curvlab — perception experiments in S3, E3 and H3"};
  app.set_version_flag("--version", std::string(curvlab::software_version()) + " (" +
                                        std::string(curvlab::git_commit()) + "), " +
                                        curvlab::harness::cli::lsl_build_line());
  app.require_subcommand(1);
  // CLI11 reads /x as an option on Windows by default; curvlab's options
  // are --x everywhere, and a positional path may begin with a slash.
  // Subcommands take this setting when they are added, below.
  app.allow_windows_style_options(false);
  curvlab::harness::cli::add_inspect_commands(app);
  curvlab::harness::cli::add_devices_commands(app);
  curvlab::harness::cli::add_export_commands(app);
  curvlab::harness::cli::add_sessions_commands(app);
  curvlab::harness::cli::add_merge_commands(app);
  curvlab::harness::cli::add_track_commands(app);
  curvlab::harness::cli::add_render_commands(app);
  curvlab::harness::cli::add_measure_commands(app);
  curvlab::harness::cli::add_protocol_commands(app);
  curvlab::harness::cli::add_authoring_commands(app);
  curvlab::harness::cli::add_run_commands(app);
  curvlab::harness::cli::add_start_command(app);
  curvlab::harness::cli::add_calibrate_commands(app);
  curvlab::harness::cli::add_billiards_commands(app);
  if (const auto wrong = curvlab::harness::cli::misspelt_argument(app, argc, argv)) {
    std::cerr << "curvlab: error: " << *wrong << '\n';
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  } catch (const curvlab::harness::cli::UsageError& e) {
    std::cerr << "curvlab: error: " << e.what() << '\n';
    return 2;
  } catch (const curvlab::harness::cli::RuntimeFailure& e) {
    std::cerr << "curvlab: " << e.what() << '\n';
    return e.exit_code;
  } catch (const std::exception& e) {
    std::cerr << "curvlab: unexpected failure: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
