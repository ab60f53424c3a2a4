// SPDX-License-Identifier: MIT
#include "cli/view_command.h"

#include <fmt/format.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>

#include "api/builtins.h"
#include "framework/error.h"
#include "view/scenario_source.h"
#include "view/server.h"

extern char** environ;

namespace harap {

namespace {

// The page's files: --assets, else share/harap/view of the install prefix (bin/../share) or of
// the build tree (build/harap beside build/share).
std::filesystem::path FindAssets(const std::string& flag) {
  if (!flag.empty()) return flag;
  std::error_code error;
  const std::filesystem::path executable = std::filesystem::canonical("/proc/self/exe", error);
  const std::filesystem::path dir = executable.parent_path();
  for (const auto& candidate :
       {dir / ".." / "share" / "harap" / "view", dir / "share" / "harap" / "view"}) {
    if (std::filesystem::is_regular_file(candidate / "index.html", error))
      return candidate.lexically_normal();
  }
  return (dir / "share" / "harap" / "view").lexically_normal();
}

// Starts the desktop's browser (xdg-open) without waiting for it; says so if there is none.
void OpenBrowser(const std::string& url) {
  const char* argv[] = {"xdg-open", url.c_str(), nullptr};
  pid_t pid = 0;
  if (posix_spawnp(&pid, "xdg-open", nullptr, nullptr, const_cast<char**>(argv), environ) != 0) {
    fmt::print(stderr, "harap view: --open: no xdg-open here; open {} in a browser\n", url);
  }
}

}  // namespace

CLI::App* AddViewCommand(CLI::App& app, ViewArguments& args) {
  auto* view = app.add_subcommand(
      "view",
      "serve an interactive page that drags a scenario's handles (or a mesh's) in the browser");
  view->add_option("file", args.file, "scenario TOML file, or a mesh file (the page adds handles)")
      ->required();
  view->add_option("--port", args.port, "port to listen on (0: any free port; default 8080)");
  view->add_option("--host", args.host,
                   "address to listen on (default 127.0.0.1: this machine only; anything else "
                   "lets the network drive the session)");
  view->add_flag("--open", args.open, "open the page in the desktop's browser (xdg-open)");
  view->add_option("--assets", args.assets,
                   "folder of the page's files (default: share/harap/view of the installation)");
  view->add_option("--config", args.config_file, "TOML file with run-config tables");
  view->add_option("--optimizer", args.optimizer,
                   "classic or hierarchical (default hierarchical: its preview frames are the "
                   "coarse approximation, the classic optimizer's a full solve)");
  view->add_option("--energy", args.energy, "energy name");
  view->add_option("--solver", args.solver, "linear solver name (default cholmod)");
  view->add_option("--preset", args.preset, "named option set (docs/solvers.md)");
  view->add_option("--tolerance", args.tolerance, "convergence tolerance of a full solve");
  view->add_option("--set", args.settings, "set any option by its config key");
  view->add_option("--threads", args.threads, "worker threads (default: all cores)");
  view->add_option("--display-vertices", args.display_vertices,
                   "the page draws at most this many vertices: a larger surface is decimated for "
                   "the display, never for the solve (default 200000)")
      ->check(CLI::Range(3, 1 << 30));
  return view;
}

int RunViewCommand(const ViewArguments& args) {
  const Registries registries = MakeBuiltinRegistries();
  ConfigNode config = args.BuildConfig();
  // Dragging streams Preview() frames: the hierarchical optimizer's are the paper's coarse
  // approximation (Figs. 15-16), the classic one's would be a full solve of the finest mesh.
  if (!config.Child("optimizer").Has("type")) config.Set("optimizer.type", "\"hierarchical\"");
  view::ViewSource source = view::LoadViewSource(args.file, config, args.threads);
  source.display_vertices = args.display_vertices;
  view::ServerOptions options;
  options.host = args.host;
  options.port = args.port;
  options.assets = FindAssets(args.assets);
  view::Server server(options, registries, source);
  if (args.host != "127.0.0.1" && args.host != "::1") {
    fmt::print(stderr,
               "harap view: warning: listening on {}: anyone who reaches this address can drive "
               "the session and read the mesh\n",
               args.host);
  }
  const std::string host =
      args.host.find(':') != std::string::npos ? "[" + args.host + "]" : args.host;
  const std::string url = fmt::format("http://{}:{}/", host, server.port());
  fmt::print("harap view: {} serves {} (Ctrl-C stops)\n", url, args.file);
  std::fflush(stdout);
  if (args.open) OpenBrowser(url);
  server.Run();
  return 0;
}

}  // namespace harap
