// The `seamvox` command: dispatches to the subcommands registered in tools/cmd_*.cpp.
#include <tbb/global_control.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "core/system/errors.h"
#include "core/system/blas_threads.h"
#include "io/interrupt_cleanup.h"
#include "tools/cli.h"

namespace {

void printHelp() {
  std::printf("seamvox: global seamless parameterization of massive triangle meshes\n\n"
              "usage: seamvox COMMAND [options]   (seamvox COMMAND --help for details)\n\n"
              "commands:\n");
  for (const auto& c : seamvox::cli::commands()) std::printf("  %-10s %s\n", c.name, c.summary);
  std::printf("\ncommon options: --threads N (worker threads), --quiet (no progress)\n");
}

}  // namespace

int main(int argc, char** argv) {
  using namespace seamvox;
  // When OpenBLAS fell back to kernels older than the processor, or the user set no OpenMP
  // thread limit, the command runs itself again with better kernels named and CHOLMOD's OpenMP
  // teams limited (same process, arguments and open files).
  rerunWithPreferredRuntime(argv);
  // SIGINT and SIGTERM remove unfinished outputs and exit 130 and 143, as a cancelled stage
  // (CancelledError) exits 130.
  installInterruptCleanup();
  setOpenMPRegionsInline(cli::openmpRegionsRunInline());
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") ||
      !std::strcmp(argv[1], "help")) {
    printHelp();
    return argc < 2 ? 2 : 0;
  }
  const std::string name = argv[1];
  const cli::Command* command = nullptr;
  for (const auto& c : cli::commands()) {
    if (name == c.name) command = &c;
  }
  if (!command) {
    std::fprintf(stderr, "seamvox: unknown command '%s' (seamvox --help lists them)\n", name.c_str());
    return 2;
  }
  std::vector<std::string> tokens(argv + 2, argv + argc);
  for (const auto& t : tokens) {
    if (t == "--help" || t == "-h") {
      std::printf("%s", command->usage);
      return 0;
    }
  }
  try {
    std::vector<std::string> flags = command->flags;
    flags.push_back("quiet");
    cli::Args args(tokens, flags);
    args.flag("quiet");  // every command accepts it; commands read it again when they show progress
    std::unique_ptr<tbb::global_control> threads;
    const std::int64_t n = args.integer("threads", 0, 1, 4096);
    limitBlasThreads(1);
    if (n > 0) {
      threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                      static_cast<std::size_t>(n));
    }
    return command->run(args);
  } catch (const cli::UsageError& e) {
    std::fprintf(stderr, "seamvox %s: %s\n\n%s", name.c_str(), e.what(), command->usage);
    return 2;
  } catch (const CancelledError& e) {
    std::fprintf(stderr, "seamvox %s: %s\n", name.c_str(), e.what());
    return 130;
  } catch (const Error& e) {
    std::fprintf(stderr, "seamvox %s: error: %s\n", name.c_str(), e.what());
    return 1;
  } catch (const std::filesystem::filesystem_error& e) {
    // A folder operation (creating, removing) that a command did not word itself: name the path.
    std::fprintf(stderr, "seamvox %s: error: %s\n", name.c_str(), cli::errorMessage(e).c_str());
    return 1;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "seamvox %s: error: out of memory\n", name.c_str());
    return 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "seamvox %s: internal error: %s\n", name.c_str(), e.what());
    return 4;
  }
}
