#pragma once
#include <CLI/CLI.hpp>

namespace chladni::cli {

// Each adds its subcommand to `app`; the callback runs it (errors propagate as exceptions).
void add_render(CLI::App& app);
void add_bench(CLI::App& app);
void add_devices(CLI::App& app);

}  // namespace chladni::cli
