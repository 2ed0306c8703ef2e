#include "chatterlab/detail/mpi_env.hpp"

#include <cstdlib>

#include <mpi.h>

namespace chatterlab {
namespace {
bool we_initialised = false;

bool launched_by_mpi() {
  for (const char* variable : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK"})
    if (std::getenv(variable) != nullptr) return true;
  return false;
}
}  // namespace

bool mpi_init_if_launched(int& argc, char**& argv) {
  if (we_initialised || !launched_by_mpi()) return we_initialised;
  int provided = 0;
  // FUNNELED: OpenMP threads compute grid points, only the main thread communicates.
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  we_initialised = true;
  return true;
}

bool mpi_active() {
  if (!we_initialised) return false;
  int finalized = 0;
  MPI_Finalized(&finalized);
  return finalized == 0;
}

int mpi_rank() {
  int rank = 0;
  if (mpi_active()) MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank;
}

int mpi_size() {
  int size = 1;
  if (mpi_active()) MPI_Comm_size(MPI_COMM_WORLD, &size);
  return size;
}

void mpi_finalize() {
  if (mpi_active()) MPI_Finalize();
}

void mpi_abort(int exit_code) {
  if (mpi_active()) MPI_Abort(MPI_COMM_WORLD, exit_code);
}

}  // namespace chatterlab
