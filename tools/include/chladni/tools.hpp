#pragma once
// Offline generators the runtime does not need. Entry points:
//   make_paper_scenario       procedural paper animations (paper_scenarios.hpp)
//   generate_paper_database   the default paper sound database (paper_db_generate.hpp)
//   default_paper_database    the same, from its cache when it reads back (paper_db_cache.hpp)
#include "chladni/tools/paper_db_cache.hpp"
#include "chladni/tools/paper_db_generate.hpp"
#include "chladni/tools/paper_scenarios.hpp"
