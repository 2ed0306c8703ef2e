#pragma once
// The few collective operations the runner needs across MPI ranks. Every function is a no-op
// (or the identity) in a single process, so run_study() has one code path for both cases.
// Only the thread that initialised MPI calls these (MPI_THREAD_FUNNELED): never from inside an
// OpenMP region.
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace chatterlab::runner {

// rank 0's `text` on every rank.
void broadcast_from_root(std::string& text);

// true on every rank iff `value` is true on every rank.
bool all_ranks_agree(bool value);

// Rank 0 receives every rank's text (index = rank); other ranks receive an empty vector.
std::vector<std::string> gather_to_root(const std::string& text);

// The other ranks' finished points on their way to rank 0 while the grid is computed
// (docs/architecture.md, "Streaming results"): a rank sends each block's records when the block
// is done, without waiting for rank 0 (which takes them between its own points, possibly long
// ones: a rank keeps the sends rank 0 has not taken yet, normally one block, never its whole
// share unless rank 0 is stuck), and rank 0 hands them to its results writer as they arrive. Messages from one rank arrive in the order they were
// sent, so an empty message closes that rank's stream. Not collective; MPI_THREAD_FUNNELED: only
// the constructing thread communicates (poll() does nothing on any other thread).
class RecordStream {
 public:
  RecordStream();
  ~RecordStream();  // waits for a send still in flight
  RecordStream(const RecordStream&) = delete;
  RecordStream& operator=(const RecordStream&) = delete;

  // A rank other than 0: sends one block's records (non-empty); does not wait.
  void send(std::string records);
  // A rank other than 0, after its last block: closes its stream.
  void close();
  // Rank 0: hands every block that has arrived to `take(rank, records)`; does not wait.
  void poll(const std::function<void(int, std::string&&)>& take);
  // Rank 0: receives until every other rank has closed its stream.
  void drain(const std::function<void(int, std::string&&)>& take);

 private:
  bool receive(bool wait, const std::function<void(int, std::string&&)>& take);
  std::thread::id owner_;
  struct Sending;
  std::vector<std::unique_ptr<Sending>> in_flight_;  // blocks not yet taken by rank 0
  void reap(bool wait);  // frees the sends that completed (all of them: waits)
  int open_ranks_ = 0;       // rank 0: other ranks whose stream is still open
};

}  // namespace chatterlab::runner
