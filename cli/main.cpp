// chladni: command-line front end. Exit codes (DESIGN.md): 0 success, 2 bad input, 3 over the
// memory budget, 1 failure.
#include <cstdio>
#include <exception>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "chladni/core/error.hpp"
#include "chladni/core/version.hpp"
#include "chladni/gpu/context.hpp"
#include "commands.hpp"
#include "native_blas.hpp"

int main(int argc, char** argv) {
  chladni::cli::exec_with_native_blas(argv);
#if defined(__GLIBC__)
  // The eigen-solve and the factorization allocate and free blocks of tens of MB at every step.
  // glibc's defaults hand such blocks back to the kernel each time (mmap above a threshold,
  // trimming the heap's top), and faulting them in again cost spot.obj's 20 s precompute 3 s.
  // Kept by the process instead; blocks of 128 MB and more are still mapped and unmapped.
  mallopt(M_MMAP_THRESHOLD, 128 << 20);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
  CLI::App app{"Chladni: GPU-accelerated modal sound synthesis"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("chladni ") + chladni::kVersion);
  chladni::cli::add_precompute(app);
  chladni::cli::add_batch(app);
  chladni::cli::add_estimate(app);
  chladni::cli::add_info(app);
  chladni::cli::add_report(app);
  chladni::cli::add_materials(app);
  chladni::cli::add_radiate(app);
  chladni::cli::add_paper(app);
  chladni::cli::add_render(app);
  chladni::cli::add_play(app);
  chladni::cli::add_shake(app);
  chladni::cli::add_bench(app);
  chladni::cli::add_devices(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  } catch (const chladni::cli::ExitCode& e) {
    return e.code;
  } catch (const chladni::BudgetError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 3;
  } catch (const chladni::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const chladni::gpu::Error& e) {
    std::fprintf(stderr, "error: Vulkan: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
