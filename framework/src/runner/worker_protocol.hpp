#pragma once
// The conversation between the runner and its worker processes (runner/worker_pool.hpp) over
// one socket per worker. Frames: a 4-byte little-endian length, then that many bytes.
//
//   runner -> worker  setup (JSON: the resolved study, output columns, threads, out_dir, plots,
//                     the input files' records), then one frame of bytes per input file sent
//   worker -> runner  {"ready": true} or {"fatal": "<why the worker cannot run>"}
//   runner -> worker  {"point": p}                       (repeated)
//   worker -> runner  {"record": "<journal line>", "compute_s": t, "output_failed": b}
//
// Results travel as journal lines, whose numbers round-trip exactly: a point computed by a
// worker gives the same results.csv bytes as one computed in the runner's own threads.
#include <optional>
#include <string>
#include <string_view>

#include "chatterlab/params.hpp"
#include "chatterlab/study.hpp"

namespace chatterlab::runner::worker {

// The hidden command line of a worker: `<executable> __worker <socket fd> <parent pid>`.
inline constexpr const char* command_name = "__worker";
inline constexpr int socket_fd = 3;

bool write_frame(int fd, std::string_view payload);  // false when the peer is gone
std::optional<std::string> read_frame(int fd);       // nullopt at end of stream or error

// A Study as JSON and back, without re-validation (the runner validated it): the worker computes
// from exactly the runner's document and grid values.
Json study_to_json(const Study& study);
Study study_from_json(const Json& json);

}  // namespace chatterlab::runner::worker
