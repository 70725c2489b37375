#pragma once
// A second BEM solver in a forked copy of this process. hmat-oss is sequential, and next to a
// solve in the main thread a second one in a thread crashed inside Debian's OpenBLAS (zgemv
// reading past a buffer that ended at a glibc thread arena's edge); a forked child is the
// single-threaded process both libraries were tested in. Its modes come back through a pipe.
// Internal to the BEM files.
#include <complex>
#include <cstddef>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "chladni/core/transfer.hpp"
#include "chladni/precompute/acoustic_transfer.hpp"

namespace chladni::precompute::bem_detail {

class SideProcess {
 public:
  using cd = std::complex<double>;
  /// What the child reports per finished mode.
  using Emit = std::function<void(std::size_t mode, const ModeTransfer&, const std::vector<cd>&)>;
  /// Forks; the child runs work(emit) and exits. receive(mode, transfer, coefficients) runs in
  /// this process, on a reader thread, once per mode the child emits.
  SideProcess(const std::function<void(const Emit&, TransferTimes&)>& work,
              std::function<void(std::size_t, const ModeTransfer&, std::vector<cd>&&)> receive);
  /// Waits for the child; adds its times. Throws InternalError if it failed or died.
  void finish(TransferTimes* times);
  /// Kills a child not finished (the caller's own half failed).
  ~SideProcess();
  SideProcess(const SideProcess&) = delete;
  SideProcess& operator=(const SideProcess&) = delete;

 private:
  void read_records();
  int pid_ = -1, fd_ = -1;
  std::function<void(std::size_t, const ModeTransfer&, std::vector<cd>&&)> receive_;
  std::thread reader_;
  TransferTimes times_;
  std::string error_;
  bool done_ = false;
};

}  // namespace chladni::precompute::bem_detail
