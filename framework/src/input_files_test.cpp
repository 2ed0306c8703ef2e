// The input-file service: SHA-256 against FIPS 180-4 vectors, a snapshot that serves the first
// bytes it read whatever happens to the file afterwards, change detection (full and by stat),
// parsed values shared, and reads outside a scope going to disk.
#include "chatterlab/input_files.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include "chatterlab/errors.hpp"
#include "chatterlab/signal_io.hpp"

namespace chatterlab {
namespace {

namespace fs = std::filesystem;

fs::path write(const std::string& name, const std::string& content) {
  fs::path dir = fs::temp_directory_path() / "chatterlab_input_files_test";
  fs::create_directories(dir);
  fs::path file = dir / name;
  std::ofstream(file, std::ios::binary | std::ios::trunc) << content;
  return file;
}

TEST(Sha256, KnownAnswers) {
  // FIPS 180-4 examples (and the well-known empty-string digest).
  EXPECT_EQ(sha256_hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(sha256_hex(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  // Message lengths around the padding boundary (55, 56, 64 bytes) differ from each other.
  EXPECT_NE(sha256_hex(std::string(55, 'x')), sha256_hex(std::string(56, 'x')));
  EXPECT_EQ(sha256_hex(std::string(64, 'a')),
            "ffe054fe7ae0cb6dc65c3af9b61d5209f439851db43d0ba5997337df154668eb");
}

TEST(InputSnapshot, ServesTheFirstBytesItReadAndRecordsTheirHash) {
  const fs::path file = write("data.csv", "x\n1\n2\n");
  auto snapshot = std::make_shared<InputSnapshot>();
  InputScope scope(snapshot);
  EXPECT_EQ(*read_input_file(file), "x\n1\n2\n");
  write("data.csv", "x\n7\n");  // replaced while the "run" goes
  EXPECT_EQ(*read_input_file(file), "x\n1\n2\n");
  EXPECT_EQ(read_data_table(file).column("x"), (std::vector<double>{1.0, 2.0}));
  ASSERT_EQ(snapshot->files().size(), 1u);
  EXPECT_EQ(snapshot->files()[0].path, input_key(file));
  EXPECT_EQ(snapshot->files()[0].sha256, sha256_hex("x\n1\n2\n"));
  EXPECT_EQ(snapshot->files()[0].bytes, 6u);

  // The change is seen: by the cheap poll (stat differs) and by the full comparison.
  std::vector<std::string> polled = snapshot->poll_changes();
  ASSERT_EQ(polled.size(), 1u);
  EXPECT_NE(polled[0].find(file.string() + ": changed since the run read it (sha256 " +
                           sha256_hex("x\n1\n2\n").substr(0, 12)),
            std::string::npos)
      << polled[0];
  EXPECT_EQ(snapshot->changes().size(), 1u);
  write("data.csv", "x\n1\n2\n");  // the same bytes again: no change
  EXPECT_TRUE(snapshot->poll_changes().empty());
  EXPECT_TRUE(snapshot->changes().empty());
  fs::remove(file);
  ASSERT_EQ(snapshot->changes().size(), 1u);
  EXPECT_NE(snapshot->changes()[0].find("can no longer be read"), std::string::npos);
}

TEST(InputSnapshot, ParsedValuesAreSharedByEveryRead) {
  const fs::path file = write("shared.csv", "a,b\n1,2\n");
  auto snapshot = std::make_shared<InputSnapshot>();
  InputScope scope(snapshot);
  int parses = 0;
  auto parse = [&](const std::string& bytes) {
    ++parses;
    return bytes.size();
  };
  auto first = read_input_parsed<std::size_t>(file, "size", parse);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&] { EXPECT_EQ(read_input_parsed<std::size_t>(file, "size", parse), first); });
  for (auto& t : threads) t.join();
  EXPECT_EQ(parses, 1);
  EXPECT_EQ(*first, 8u);
}

TEST(InputSnapshot, WithoutAScopeReadsGoToDisk) {
  const fs::path file = write("direct.csv", "1\n");
  EXPECT_EQ(current_input_snapshot(), nullptr);
  EXPECT_EQ(*read_input_file(file), "1\n");
  write("direct.csv", "2\n");
  EXPECT_EQ(*read_input_file(file), "2\n");
}

TEST(InputSnapshot, StudyFilesAreRecordedButNotVerified) {
  const fs::path study = write("s.toml", "[study]\n");
  auto snapshot = std::make_shared<InputSnapshot>();
  snapshot->read(study, InputRole::study);
  write("s.toml", "# a comment\n[study]\n");
  EXPECT_TRUE(snapshot->changes().empty());  // the resolved study is what resume compares
  EXPECT_TRUE(snapshot->poll_changes().empty());
}

TEST(InputSnapshot, AddedBytesMustMatchTheirHash) {
  InputSnapshot snapshot;
  InputFileRecord record{"/nonexistent/x.csv", InputRole::data, 3, sha256_hex("abc")};
  snapshot.add(record, std::make_shared<const std::string>("abc"));
  EXPECT_EQ(*snapshot.bytes_of("/nonexistent/x.csv"), "abc");
  EXPECT_THROW(snapshot.add(record, std::make_shared<const std::string>("abd")),
               std::invalid_argument);
}

TEST(InputFiles, MessagesNameTheFile) {
  auto message = [](const fs::path& file) {
    try {
      read_input_file(file);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message("/nonexistent/x.csv"), "/nonexistent/x.csv: no such file");
  EXPECT_EQ(message(fs::temp_directory_path()),
            fs::temp_directory_path().string() + ": is a directory, not a data file");
  InputFileStream missing("/nonexistent/x.csv");
  EXPECT_FALSE(missing);
  InputFileStream present(write("stream.txt", "hello world"));
  std::string word;
  present >> word;
  EXPECT_EQ(word, "hello");
}

}  // namespace
}  // namespace chatterlab
