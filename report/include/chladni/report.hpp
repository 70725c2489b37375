#pragma once
// A soundbank inspected. Entry points:
//   mode_facts, bank_json       each mode's facts under one set of names (bank_facts.hpp)
//   gains_towards               a mode's gain by direction, by the runtime's rule (radiation.hpp)
//   write_report                the bank as a self-contained HTML page (report.hpp)
#include "chladni/report/bank_facts.hpp"
#include "chladni/report/radiation.hpp"
#include "chladni/report/report.hpp"
