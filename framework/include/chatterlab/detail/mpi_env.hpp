#pragma once
// MPI for `mpirun -np N chatterlab run ...`, and nothing for a plain `chatterlab run ...`.
// MPI is initialised only when a launcher started the process (OpenMPI's mpirun sets
// OMPI_COMM_WORLD_SIZE, PMIx launchers PMIX_RANK, Hydra PMI_RANK): a singleton MPI_Init outside
// mpirun is slow, noisy and fails on machines without a working network stack, and the command
// must work everywhere. Without MPI the process is rank 0 of 1.
namespace chatterlab {

// Called once by main() before anything else reads rank/size. Returns true when MPI was
// initialised (with MPI_THREAD_FUNNELED: only the thread that called this uses MPI).
bool mpi_init_if_launched(int& argc, char**& argv);

// True between a successful mpi_init_if_launched and mpi_finalize.
bool mpi_active();
int mpi_rank();  // 0 without MPI
int mpi_size();  // 1 without MPI

// Finalizes MPI if mpi_init_if_launched initialised it; safe to call more than once.
void mpi_finalize();

// Ends every rank with `exit_code` (MPI_Abort) when MPI is active; otherwise does nothing and
// returns. For errors raised on some ranks only, where the others would wait forever in a
// collective call.
void mpi_abort(int exit_code);

}  // namespace chatterlab
