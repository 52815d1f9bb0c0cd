// How the ranks agree on a failure before anyone throws: a failure found on one rank (a bad
// argument, a vanishing pivot) is reduced over the communicator, and every rank throws the same
// exception. No rank leaves a collective that the others then wait in forever.
#pragma once

#include <mpi.h>

#include <climits>
#include <cstddef>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include "tridiff/solvers/error.hpp"

namespace tridiff::distributed::detail {

// What went wrong on this rank, if anything. `stage` orders failures of one call: the earliest
// stage wins (a reduced system that broke down because another rank's rows were invalid is not
// the news), then the lowest rank.
struct Failure {
  enum Kind : int { None = 0, Invalid = 1, Numerical = 2, Other = 3 };
  int kind = None;
  int stage = 0;
  long long system = -1, row = -1;
  std::string argument, message;

  explicit operator bool() const { return kind != None; }
};

// Runs `step` and turns what it throws into a Failure of `stage` (a failure already recorded
// is kept: it is earlier).
template <class Step>
void capture(Failure& failure, int stage, Step&& step) {
  if (failure) return;
  try {
    step();
  } catch (const InvalidArgument& e) {
    failure = {Failure::Invalid, stage, e.system(), e.row(), e.argument(), e.message()};
  } catch (const NumericalError& e) {
    // what() already names the system and row; keep only the message after them.
    std::string text = e.what();
    const auto colon = text.find(": ", text.find(": ") + 2);
    failure = {Failure::Numerical,
               stage,
               e.system(),
               e.row(),
               "",
               e.system() >= 0 && colon != std::string::npos ? text.substr(colon + 2) : text};
  } catch (const std::bad_alloc&) {
    failure = {Failure::Other, stage, -1, -1, "", "out of memory"};
  } catch (const std::exception& e) {
    failure = {Failure::Other, stage, -1, -1, "", e.what()};
  }
}

inline void broadcast_string(std::string& text, int root, MPI_Comm comm) {
  int length = static_cast<int>(text.size());
  MPI_Bcast(&length, 1, MPI_INT, root, comm);
  text.resize(length);
  MPI_Bcast(text.data(), length, MPI_CHAR, root, comm);
}

// Collective: returns if no rank failed; otherwise every rank throws the chosen failure,
// saying on which rank it was found.
inline void agree(const Failure& local, MPI_Comm comm) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  long long key = local ? static_cast<long long>(local.stage) * size + rank : LLONG_MAX;
  MPI_Allreduce(MPI_IN_PLACE, &key, 1, MPI_LONG_LONG, MPI_MIN, comm);
  if (key == LLONG_MAX) return;
  const int root = static_cast<int>(key % size);
  Failure chosen = local;
  long long numbers[3] = {chosen.kind, chosen.system, chosen.row};
  MPI_Bcast(numbers, 3, MPI_LONG_LONG, root, comm);
  broadcast_string(chosen.argument, root, comm);
  broadcast_string(chosen.message, root, comm);
  const std::string where = " (found on rank " + std::to_string(root) + ")";
  const auto system = static_cast<std::ptrdiff_t>(numbers[1]);
  const auto row = static_cast<std::ptrdiff_t>(numbers[2]);
  switch (numbers[0]) {
    case Failure::Invalid:
      throw InvalidArgument(chosen.argument, system, row, chosen.message + where);
    case Failure::Numerical: throw NumericalError(system, row, chosen.message + where);
    default: throw Error("tridiff: " + chosen.message + where);
  }
}

}  // namespace tridiff::distributed::detail
