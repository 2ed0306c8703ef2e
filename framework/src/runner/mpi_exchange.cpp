#include "runner/mpi_exchange.hpp"

#include <mpi.h>

#include <climits>
#include <memory>
#include <vector>
#include <stdexcept>

#include "chatterlab/detail/mpi_env.hpp"

namespace chatterlab::runner {

namespace {
bool distributed() { return mpi_size() > 1; }

int checked_count(std::size_t n) {
  // MPI counts are int; a rank's share of a grid under the 10^7-point limit stays far below.
  if (n > static_cast<std::size_t>(INT_MAX))
    throw std::runtime_error("runner: MPI message over 2 GiB");
  return static_cast<int>(n);
}
}  // namespace

void broadcast_from_root(std::string& text) {
  if (!distributed()) return;
  unsigned long long size = text.size();
  MPI_Bcast(&size, 1, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD);
  text.resize(static_cast<std::size_t>(size));
  if (size > 0) MPI_Bcast(text.data(), checked_count(text.size()), MPI_CHAR, 0, MPI_COMM_WORLD);
}

bool all_ranks_agree(bool value) {
  if (!distributed()) return value;
  int mine = value ? 1 : 0, all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_LAND, MPI_COMM_WORLD);
  return all != 0;
}

std::vector<std::string> gather_to_root(const std::string& text) {
  if (!distributed()) return {text};
  const int size = mpi_size(), rank = mpi_rank();
  int mine = checked_count(text.size());
  std::vector<int> counts(rank == 0 ? static_cast<std::size_t>(size) : 0);
  MPI_Gather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::vector<int> offsets(counts.size());
  std::size_t total = 0;
  for (std::size_t r = 0; r < counts.size(); ++r) {
    offsets[r] = checked_count(total);
    total += static_cast<std::size_t>(counts[r]);
  }
  std::string all(total, '\0');
  MPI_Gatherv(text.data(), mine, MPI_CHAR, all.data(), counts.data(), offsets.data(), MPI_CHAR, 0,
              MPI_COMM_WORLD);
  std::vector<std::string> out;
  for (std::size_t r = 0; r < counts.size(); ++r)
    out.push_back(
        all.substr(static_cast<std::size_t>(offsets[r]), static_cast<std::size_t>(counts[r])));
  return out;
}

namespace {
// The tag of RecordStream's messages (the scheduler uses one-sided operations, the other
// functions here collectives: nothing else uses point-to-point tags).
constexpr int record_tag = 23;
}  // namespace

struct RecordStream::Sending {
  std::string records;
  MPI_Request request = MPI_REQUEST_NULL;
};

RecordStream::RecordStream()
    : owner_(std::this_thread::get_id()), open_ranks_(mpi_rank() == 0 ? mpi_size() - 1 : 0) {}

RecordStream::~RecordStream() {
  if (mpi_active()) reap(/*wait=*/true);
}

void RecordStream::reap(bool wait) {
  std::erase_if(in_flight_, [&](const std::unique_ptr<Sending>& sending) {
    int done = 0;
    if (wait)
      MPI_Wait(&sending->request, MPI_STATUS_IGNORE);
    else
      MPI_Test(&sending->request, &done, MPI_STATUS_IGNORE);
    return wait || done != 0;
  });
}

void RecordStream::send(std::string records) {
  if (!distributed() || records.empty()) return;
  reap(/*wait=*/false);
  auto sending = std::make_unique<Sending>();
  sending->records = std::move(records);
  MPI_Isend(sending->records.data(), checked_count(sending->records.size()), MPI_CHAR, 0,
            record_tag, MPI_COMM_WORLD, &sending->request);
  in_flight_.push_back(std::move(sending));
}

void RecordStream::close() {
  if (!distributed()) return;
  reap(/*wait=*/true);
  MPI_Send(nullptr, 0, MPI_CHAR, 0, record_tag, MPI_COMM_WORLD);
}

bool RecordStream::receive(bool wait, const std::function<void(int, std::string&&)>& take) {
  MPI_Status status;
  int arrived = 1;
  if (wait)
    MPI_Probe(MPI_ANY_SOURCE, record_tag, MPI_COMM_WORLD, &status);
  else
    MPI_Iprobe(MPI_ANY_SOURCE, record_tag, MPI_COMM_WORLD, &arrived, &status);
  if (!arrived) return false;
  int count = 0;
  MPI_Get_count(&status, MPI_CHAR, &count);
  std::string records(static_cast<std::size_t>(count), '\0');
  MPI_Recv(records.data(), count, MPI_CHAR, status.MPI_SOURCE, record_tag, MPI_COMM_WORLD,
           MPI_STATUS_IGNORE);
  if (records.empty())
    --open_ranks_;
  else
    take(status.MPI_SOURCE, std::move(records));
  return true;
}

void RecordStream::poll(const std::function<void(int, std::string&&)>& take) {
  if (!distributed() || mpi_rank() != 0 || std::this_thread::get_id() != owner_) return;
  while (open_ranks_ > 0 && receive(false, take)) {
  }
}

void RecordStream::drain(const std::function<void(int, std::string&&)>& take) {
  if (!distributed() || mpi_rank() != 0) return;
  while (open_ranks_ > 0) receive(true, take);
}

}  // namespace chatterlab::runner
