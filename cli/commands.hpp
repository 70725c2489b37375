#pragma once
#include <CLI/CLI.hpp>

namespace chladni::cli {

// Each adds its subcommand to `app`; the callback runs it (errors propagate as exceptions).
void add_render(CLI::App& app);
void add_bench(CLI::App& app);
void add_devices(CLI::App& app);
void add_precompute(CLI::App& app);
void add_materials(CLI::App& app);
void add_info(CLI::App& app);
void add_radiate(CLI::App& app);
void add_paper(CLI::App& app);
void add_shake(CLI::App& app);

}  // namespace chladni::cli
