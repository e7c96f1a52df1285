// All-or-nothing outputs (io/output_set.h): every target is replaced or none is, whatever fails
// (a write, a move), and no temporary is left behind; isSameFile for the clobbering checks.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "core/system/errors.h"
#include "io/atomic_file.h"
#include "io/output_set.h"
#include "testing.h"

namespace seamvox {
namespace {

using ::testing::HasSubstr;
using testing::readFile;
using testing::TempDir;
using testing::writeFile;
namespace fs = std::filesystem;

TEST(OutputSet, AnAdoptedFileIsMovedInPlaceOnlyOnCommit) {
  TempDir dir;
  const std::string target = dir.path("map.ply"), finished = dir.path("staged/map.ply");
  fs::create_directories(dir.path("staged"));
  writeFile(target, "old");
  {
    OutputSet outputs;
    AtomicFile& file = outputs.add(target);
    file.write("ignored: the adopted file replaces what was written");
    writeFile(finished, "made elsewhere");
    file.adopt(finished);
    EXPECT_FALSE(fs::exists(finished)) << "moved, not copied";
    EXPECT_EQ(readFile(target), "old");
  }  // not committed: the adopted content goes with the temporary
  EXPECT_EQ(readFile(target), "old");
  EXPECT_TRUE(testing::temporaryFilesIn(dir.dir()).empty());
  OutputSet outputs;
  writeFile(finished, "made elsewhere");
  outputs.add(target).adopt(finished);
  outputs.commit();
  EXPECT_EQ(readFile(target), "made elsewhere");
  EXPECT_TRUE(testing::temporaryFilesIn(dir.dir()).empty());
  std::string message;
  try {
    OutputSet more;
    more.add(target).adopt(dir.path("missing"));
  } catch (const IoError& e) {
    message = e.what();
  }
  EXPECT_THAT(message, HasSubstr("missing"));
}

TEST(OutputSet, CommitReplacesAndCreatesEveryTarget) {
  TempDir dir;
  const std::string a = dir.path("a.txt"), b = dir.path("b.txt");
  writeFile(a, "old a");
  {
    OutputSet outputs;
    outputs.add(a).write("new a");
    outputs.add(b).write("new b");
    // Staged, not yet visible.
    EXPECT_EQ(readFile(a), "old a");
    EXPECT_FALSE(fs::exists(b));
    EXPECT_EQ(testing::temporaryFilesIn(dir.dir()).size(), 2u);
    outputs.commit();
  }
  EXPECT_EQ(readFile(a), "new a");
  EXPECT_EQ(readFile(b), "new b");
  EXPECT_THAT(testing::temporaryFilesIn(dir.dir()), ::testing::IsEmpty());
}

TEST(OutputSet, UncommittedSetTouchesNoTarget) {
  TempDir dir;
  const std::string a = dir.path("a.txt"), b = dir.path("b.txt");
  writeFile(a, "old a");
  try {
    OutputSet outputs;
    outputs.add(a).write("new a");
    outputs.add(b).write("new b");
    throw InputError("a stage failed");
  } catch (const InputError&) {
  }
  EXPECT_EQ(readFile(a), "old a");
  EXPECT_FALSE(fs::exists(b));
  EXPECT_THAT(testing::temporaryFilesIn(dir.dir()), ::testing::IsEmpty());
}

TEST(OutputSet, AFailedMovePutsTheOthersBack) {
  TempDir dir;
  const std::string a = dir.path("a.txt"), b = dir.path("b.txt"), c = dir.path("c.txt");
  writeFile(a, "old a");
  OutputSet outputs;
  outputs.add(a).write("new a");
  outputs.add(b).write("new b");
  outputs.add(c).write("new c");
  fs::create_directory(c);  // appears after staging: the third move fails
  std::string message;
  try {
    outputs.commit();
  } catch (const IoError& e) {
    message = e.what();
  }
  EXPECT_THAT(message, HasSubstr(c));
  EXPECT_EQ(readFile(a), "old a") << "the replaced target is exchanged back";
  EXPECT_FALSE(fs::exists(b)) << "the created target is removed";
  EXPECT_TRUE(fs::is_directory(c));
  EXPECT_THAT(testing::temporaryFilesIn(dir.dir()), ::testing::IsEmpty());
}

// The exit code of body run in a child process whose files may not grow beyond `bytes` (SIGXFSZ
// ignored, so writes fail with EFBIG as on a full disk); -1 when the child did not exit.
template <class Body>
int exitCodeWithFileSizeLimit(rlim_t bytes, Body&& body) {
  const pid_t pid = fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{bytes, bytes};
    setrlimit(RLIMIT_FSIZE, &limit);
    _exit(body());
  }
  int status = 0;
  if (waitpid(pid, &status, 0) != pid || !WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

TEST(OutputSet, AFailedWriteLeavesEveryTargetAsItWas) {
  // Files limited to 64 KiB: the small output is written, the large one fails.
  TempDir dir;
  const std::string small = dir.path("small.txt"), large = dir.path("large.bin");
  writeFile(small, "old small");
  const int code = exitCodeWithFileSizeLimit(64 << 10, [&] {
    try {
      OutputSet outputs;
      outputs.add(small).write("new small");
      outputs.add(large).write(std::string(1 << 20, 'x'));
      outputs.commit();
    } catch (const IoError&) {
      return 0;
    }
    return 1;
  });
  EXPECT_EQ(code, 0) << "the failed write must throw IoError";
  EXPECT_EQ(readFile(small), "old small");
  EXPECT_FALSE(fs::exists(large));
  EXPECT_THAT(testing::temporaryFilesIn(dir.dir()), ::testing::IsEmpty());
}

TEST(AtomicFile, AWriteFailingOnItsWriterThreadIsAnErrorNamingTheOutput) {
  // Output of many buffers (the writer thread writes them) into a file that may not grow beyond
  // 1 MiB: the failure reaches the caller as IoError, and neither the target nor the temporary
  // is left.
  TempDir dir;
  const std::string large = dir.path("large.bin");
  const int code = exitCodeWithFileSizeLimit(1 << 20, [&] {
    try {
      AtomicFile file(large);
      const std::string piece(64 << 10, 'x');
      for (int i = 0; i < 512; ++i) file.write(piece);  // 32 MiB
      file.commit();
    } catch (const IoError& e) {
      const std::string message = e.what();
      return message.find(large) != std::string::npos && message.find("write failed") != std::string::npos ? 0 : 2;
    }
    return 1;
  });
  EXPECT_EQ(code, 0) << "the failed write must throw IoError naming the output (2: another message)";
  EXPECT_FALSE(fs::exists(large));
  EXPECT_THAT(testing::temporaryFilesIn(dir.dir()), ::testing::IsEmpty());
}

TEST(AtomicFile, ManyBuffersArriveInOrder) {
  TempDir dir;
  std::string expected;
  {
    AtomicFile file(dir.path("out.bin"));
    for (int i = 0; i < 3000; ++i) {
      const std::string piece(1 + (i * 7919) % 20000, static_cast<char>('a' + i % 26));
      file.write(piece);
      expected += piece;
    }
    file.commit();
  }
  EXPECT_GT(expected.size(), std::size_t(16) << 20) << "several 4 MiB buffers";
  EXPECT_TRUE(readFile(dir.path("out.bin")) == expected);
}

TEST(OutputSet, FoldersAndTargetsStagedTwiceAreRefused) {
  TempDir dir;
  OutputSet outputs;
  EXPECT_THROW(outputs.add(dir.dir()), IoError);
  outputs.add(dir.path("a.txt"));
  EXPECT_THROW(outputs.add(dir.dir() + "/./a.txt"), IoError);
  EXPECT_THROW(outputs.add(dir.path("missing/a.txt")), IoError);
  EXPECT_EQ(outputs.size(), 1u);
}

TEST(OutputSet, SameFileThroughLinksDotsAndMissingFiles) {
  TempDir dir;
  const std::string a = dir.path("a.txt");
  writeFile(a, "a");
  fs::create_directory(dir.path("sub"));
  fs::create_symlink(a, dir.path("link.txt"));
  fs::create_hard_link(a, dir.path("hard.txt"));
  EXPECT_TRUE(isSameFile(a, dir.path("sub/../a.txt")));
  EXPECT_TRUE(isSameFile(a, dir.path("link.txt")));
  EXPECT_TRUE(isSameFile(a, dir.path("hard.txt")));
  EXPECT_TRUE(isSameFile(dir.path("new.txt"), dir.path("sub/../new.txt")));
  EXPECT_FALSE(isSameFile(a, dir.path("new.txt")));
  EXPECT_FALSE(isSameFile(dir.path("new.txt"), dir.path("sub/new.txt")));
}

}  // namespace
}  // namespace seamvox
