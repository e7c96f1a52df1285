// Scratch folders (stream/scratch_folder) and the external sort (stream/external_sort): the
// sort against std::sort with many runs and merge rounds, the disk-full path, and the folder
// removed on success, on an exception and on SIGINT.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <random>
#include <tuple>

#include "core/system/errors.h"
#include "io/interrupt_cleanup.h"
#include "stream/external_sort.h"
#include "stream/keyed_sort.h"
#include "stream/scratch_folder.h"
#include "testing.h"

namespace seamvox {
namespace {

namespace fs = std::filesystem;

struct Record {
  std::uint64_t key;
  std::uint32_t id, payload;
};
struct ByKeyThenId {
  bool operator()(const Record& a, const Record& b) const { return std::tie(a.key, a.id) < std::tie(b.key, b.id); }
};

std::vector<Record> randomRecords(std::size_t n, std::uint64_t keys, std::uint32_t seed) {
  std::mt19937_64 random(seed);
  std::vector<Record> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = {random() % keys, static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(random())};
  }
  return out;
}

std::size_t filesIn(const std::string& dir) {
  return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

// Sorts records with an external sorter of the given memory limit; returns what next() gave.
std::vector<Record> externalSort(ScratchFolder& scratch, const std::vector<Record>& records,
                                 std::uint64_t memoryBytes, std::size_t* runs = nullptr) {
  ExternalSorter<Record, ByKeyThenId> sorter(scratch, {memoryBytes, "test"});
  for (const Record& r : records) sorter.add(r);
  sorter.finish();
  EXPECT_EQ(sorter.size(), records.size());
  std::vector<Record> out;
  Record r;
  while (sorter.next(r)) out.push_back(r);
  if (runs) *runs = sorter.runs();
  return out;
}

void expectSameRecords(const std::vector<Record>& a, const std::vector<Record>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_TRUE(a[i].key == b[i].key && a[i].id == b[i].id && a[i].payload == b[i].payload) << "record " << i;
  }
}

TEST(ExternalSort, TinyLimitManyRunsAndMergeRoundsEqualsStdSort) {
  testing::TempDir dir;
  for (const std::uint64_t keys : {std::uint64_t(7), std::uint64_t(1) << 40}) {  // many ties, few ties
    std::vector<Record> records = randomRecords(60000, keys, 17);
    std::vector<Record> expected = records;
    std::sort(expected.begin(), expected.end(), ByKeyThenId{});
    ScratchFolder scratch(dir.dir());
    std::size_t runs = 0;
    const std::vector<Record> sorted = externalSort(scratch, records, 4096, &runs);
    expectSameRecords(sorted, expected);
    // 4 KiB holds 128 records per run and merges 64 runs at once: several merge rounds.
    EXPECT_GE(runs, 400u);
    EXPECT_GT(scratch.traffic().at(0).bytesWritten, 3 * records.size() * sizeof(Record) / 2)
        << "runs and intermediate rounds (64 runs each) are written";
    EXPECT_EQ(scratch.bytesOnDisk(), scratch.bytesKeptForReuse()) << "every run is removed once merged";
    EXPECT_LT(scratch.peakBytesOnDisk(), scratch.traffic().at(0).bytesWritten) << "merge rounds overwrite merged runs";
  }
}

TEST(ExternalSort, InputWithinTheLimitNeverTouchesTheDisk) {
  testing::TempDir dir;
  ScratchFolder scratch(dir.dir());
  std::vector<Record> records = randomRecords(1000, 100, 3), expected = records;
  std::sort(expected.begin(), expected.end(), ByKeyThenId{});
  std::size_t runs = 1;
  expectSameRecords(externalSort(scratch, records, 1 << 20, &runs), expected);
  EXPECT_EQ(runs, 0u);
  EXPECT_EQ(scratch.bytesWritten(), 0u);
}

TEST(ExternalSort, EmptyAndSingleRecordInputs) {
  testing::TempDir dir;
  ScratchFolder scratch(dir.dir());
  EXPECT_TRUE(externalSort(scratch, {}, 64).empty());
  const std::vector<Record> one = {{5, 1, 2}};
  expectSameRecords(externalSort(scratch, one, 16), one);
}

// The final merge runs ahead on a thread of its own: a reader that stops early ends it, and a
// run cut short while it is merged is the reader's error, not the thread's.
TEST(ExternalSort, TheMergeAheadStopsWithItsReaderAndHandsOverErrors) {
  testing::TempDir dir;
  {
    ScratchFolder scratch(dir.dir());
    {
      ExternalSorter<Record, ByKeyThenId> sorter(scratch, {4096, "test"});
      for (const Record& r : randomRecords(60000, 1000, 9)) sorter.add(r);
      sorter.finish();
      Record r;
      for (int i = 0; i < 10; ++i) ASSERT_TRUE(sorter.next(r));
    }
    EXPECT_EQ(scratch.bytesOnDisk(), scratch.bytesKeptForReuse()) << "the runs are removed";
  }
  ScratchFolder scratch(dir.dir());
  ExternalSorter<Record, ByKeyThenId> sorter(scratch, {1 << 16, "test"});
  for (const Record& r : randomRecords(60000, 1000, 11)) sorter.add(r);
  sorter.finish();
  ASSERT_GT(sorter.runs(), 1u);
  // Every run (2048 records) cut inside its 1000th record: far beyond what the merge has read
  // ahead (blocks of 32 records).
  for (const auto& entry : fs::directory_iterator(scratch.path())) {
    if (entry.is_regular_file() && entry.file_size() > 1000 * sizeof(Record)) {
      fs::resize_file(entry.path(), 999 * sizeof(Record) + 5);
    }
  }
  Record r;
  std::size_t served = 0;
  try {
    while (sorter.next(r)) ++served;
    FAIL() << "the cut runs were merged to the end (" << served << " records)";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("ends inside a record"), std::string::npos) << e.what();
  }
  EXPECT_LT(served, 60000u);
}

TEST(ExternalSort, DiskFullNamesTheFolderAndTheBytesNeededAndLeavesNothing) {
  testing::TempDir dir;
  std::string folder;
  try {
    ScratchFolder scratch(dir.dir(), 123456789);
    folder = scratch.path();
    scratch.setWriteLimit(20000);
    externalSort(scratch, randomRecords(50000, 1000, 5), 4096);
    FAIL() << "the write limit was never reached";
  } catch (const IoError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(folder), std::string::npos) << message;
    EXPECT_NE(message.find("is full"), std::string::npos) << message;
    EXPECT_NE(message.find("117.7 MiB"), std::string::npos) << "the bytes the run needs: " << message;
    EXPECT_NE(message.find("--scratch"), std::string::npos) << message;
  }
  EXPECT_FALSE(folder.empty());
  EXPECT_FALSE(fs::exists(folder)) << "the scratch folder is removed when the error unwinds";
  EXPECT_EQ(filesIn(dir.dir()), 0u);
}

struct KeyOf {
  std::uint64_t operator()(const Record& r) const { return r.key; }
};

// Sorts records with a keyed sorter (keys below keyCount), twice through rewind(); both passes
// must give the same records.
std::vector<Record> keyedSort(ScratchFolder& scratch, const std::vector<Record>& records, std::uint64_t keyCount,
                              std::uint64_t expected, std::uint64_t memoryBytes, std::size_t* files = nullptr) {
  KeyedSorter<Record, ByKeyThenId, KeyOf> sorter(scratch, keyCount, expected, {memoryBytes, "test"});
  for (const Record& r : records) sorter.add(r);
  sorter.finish();
  EXPECT_EQ(sorter.size(), records.size());
  std::vector<Record> out, again;
  Record r;
  while (sorter.next(r)) out.push_back(r);
  sorter.rewind();
  while (sorter.next(r)) again.push_back(r);
  expectSameRecords(again, out);
  if (files) *files = sorter.filesWritten();
  return out;
}

// In memory, in partitions of key ranges, with a key holding half the records (its partition over
// the limit: the external sort), and with far more records than announced: std::sort's order.
// The input runs from the largest id down, so each key's records need their own sort.
TEST(KeyedSort, EqualsStdSortInMemoryInPartitionsAndPastTheLimit) {
  testing::TempDir dir;
  const std::uint64_t keys = 5000;
  std::vector<Record> spread = randomRecords(60000, keys, 29), skewed = spread, bunched = spread;
  for (std::size_t i = 0; i < skewed.size(); i += 2) skewed[i].key = 17;
  for (Record& r : bunched) r.key = 1000 + r.key % 1000;  // a fifth of the key range
  for (std::vector<Record>* records : {&spread, &skewed, &bunched}) std::reverse(records->begin(), records->end());
  struct Case {
    const char* name;
    const std::vector<Record>& records;
    std::uint64_t expected, memory;
    bool inMemory;
  };
  const std::uint64_t bytes = spread.size() * sizeof(Record);
  for (const Case& c : {Case{"in memory", spread, spread.size(), 64u << 20, true},
                        Case{"partitions", spread, spread.size(), 64u << 10, false},
                        Case{"one large key", skewed, skewed.size(), 256u << 10, false},
                        Case{"bunched keys", bunched, bunched.size(), 256u << 10, false},
                        Case{"more than announced", spread, 100, 64u << 10, false}}) {
    SCOPED_TRACE(c.name);
    ScratchFolder scratch(dir.dir());
    std::vector<Record> expected = c.records;
    std::sort(expected.begin(), expected.end(), ByKeyThenId{});
    std::size_t files = 0;
    expectSameRecords(keyedSort(scratch, c.records, keys, c.expected, c.memory, &files), expected);
    if (c.inMemory) {
      EXPECT_EQ(files, 0u);
      EXPECT_EQ(scratch.bytesWritten(), 0u);
      continue;
    }
    EXPECT_GE(files, 1u);
    if (std::string(c.name) == "partitions" || std::string(c.name) == "bunched keys") {
      EXPECT_GT(files, 20u);  // 64 or 256 KiB for 1.9 MB of records
      // Written once, read once per pass (two passes): no runs, no merge rounds. Bunched keys
      // fill a fifth of the partitions, sorted a few at a time: none over the limit.
      EXPECT_EQ(scratch.traffic().at(0).bytesWritten, bytes);
      EXPECT_EQ(scratch.traffic().at(0).bytesRead, 2 * bytes);
    } else {
      EXPECT_GT(scratch.traffic().at(0).bytesWritten, bytes) << "the partition over the limit is sorted in runs";
    }
  }
  ScratchFolder scratch(dir.dir());
  KeyedSorter<Record, ByKeyThenId, KeyOf> sorter(scratch, keys, 10, {1u << 20, "test"});
  EXPECT_THROW(sorter.add(Record{keys, 0, 0}), std::out_of_range);
  sorter.finish();
  Record r;
  EXPECT_FALSE(sorter.next(r));
}

TEST(ScratchFolder, FilesRoundTripAndTrafficIsCountedPerStage) {
  testing::TempDir dir;
  ScratchFolder scratch(dir.dir());
  EXPECT_EQ(fs::path(scratch.path()).parent_path(), fs::path(dir.dir()));
  ScratchWriter writer(scratch, "write", 4096);
  for (std::uint32_t i = 0; i < 10000; ++i) writer.write(&i, sizeof i);
  const ScratchFile file = writer.finish();
  EXPECT_EQ(file.bytes, 40000u);
  EXPECT_EQ(fs::file_size(file.path), 40000u);
  ScratchReader reader(scratch, file, "read", 100);
  std::uint32_t x = 0;
  for (std::uint32_t i = 0; i < 10000; ++i) {
    ASSERT_TRUE(reader.read(&x, sizeof x));
    ASSERT_EQ(x, i);
  }
  EXPECT_FALSE(reader.read(&x, sizeof x));
  ASSERT_EQ(scratch.traffic().size(), 2u);
  EXPECT_EQ(scratch.traffic()[0].stage, "write");
  EXPECT_EQ(scratch.traffic()[0].bytesWritten, 40000u);
  EXPECT_EQ(scratch.traffic()[1].bytesRead, 40000u);
  EXPECT_EQ(scratch.peakBytesOnDisk(), 40000u);
}

TEST(ScratchFolder, ARemovedFileIsOverwrittenByTheNextWriterAndReadOnlyToItsNewEnd) {
  testing::TempDir dir;
  ScratchFolder scratch(dir.dir());
  auto writeCount = [&](std::uint32_t from, std::uint32_t count, std::uint64_t expected) {
    auto writer = std::make_unique<ScratchWriter>(scratch, "write", 4096, expected);
    for (std::uint32_t i = from; i < from + count; ++i) writer->write(&i, sizeof i);
    return writer;
  };
  const ScratchFile first = writeCount(0, 10000, 0)->finish();
  scratch.remove(first);
  EXPECT_EQ(scratch.bytesOnDisk(), 40000u) << "kept for reuse";
  EXPECT_EQ(scratch.bytesKeptForReuse(), 40000u);
  // A writer of a quarter of it takes another file (a larger one may come for this one).
  const ScratchFile quarter = writeCount(0, 2500, 10000)->finish();
  EXPECT_NE(quarter.path, first.path);
  // A writer of 6000 records (unknown size) overwrites it; 4000 stale records stay past its end
  // while it is written, and a reader of what it wrote so far stops there.
  const auto reuser = writeCount(100000, 3000, 0);
  const ScratchFile partial = reuser->written();
  EXPECT_EQ(partial.path, first.path);
  EXPECT_EQ(partial.bytes, 12000u);
  EXPECT_EQ(fs::file_size(partial.path), 40000u);
  {
    ScratchReader reader(scratch, partial, "read", 100);
    std::uint32_t x = 0, n = 0;
    while (reader.read(&x, sizeof x)) ASSERT_EQ(x, 100000u + n++);
    EXPECT_EQ(n, 3000u);
  }
  for (std::uint32_t i = 103000; i < 106000; ++i) reuser->write(&i, sizeof i);
  const ScratchFile second = reuser->finish();
  EXPECT_EQ(second.bytes, 24000u);
  EXPECT_EQ(fs::file_size(second.path), 24000u) << "truncated to what it wrote";
  EXPECT_EQ(scratch.bytesOnDisk(), 24000u + 10000u);
  EXPECT_EQ(scratch.peakBytesOnDisk(), 50000u);
  ScratchReader reader(scratch, second, "read", 100);
  std::uint32_t x = 0, n = 0;
  while (reader.read(&x, sizeof x)) ASSERT_EQ(x, 100000u + n++);
  EXPECT_EQ(n, 6000u);
  // Grown past the file it took: counted as it grows.
  scratch.remove(quarter);
  const ScratchFile grown = writeCount(0, 5000, 0)->finish();
  EXPECT_EQ(grown.path, quarter.path);
  EXPECT_EQ(fs::file_size(grown.path), 20000u);
  EXPECT_EQ(scratch.bytesOnDisk(), 24000u + 20000u);
}

TEST(ScratchFolder, AFileRemovedWhileItsReaderIsOpenIsNotOverwritten) {
  testing::TempDir dir;
  ScratchFolder scratch(dir.dir());
  ScratchWriter writer(scratch, "write", 4096);
  for (std::uint32_t i = 0; i < 10000; ++i) writer.write(&i, sizeof i);
  const ScratchFile file = writer.finish();
  ScratchReader reader(scratch, file, "read", 64);
  scratch.remove(file);  // the reader still reads it
  EXPECT_EQ(scratch.bytesKeptForReuse(), 0u);
  EXPECT_EQ(scratch.bytesOnDisk(), 0u);
  ScratchWriter other(scratch, "write", 4096);
  for (std::uint32_t i = 0; i < 10000; ++i) other.write(&i, sizeof i);  // the same size
  const ScratchFile second = other.finish();
  EXPECT_NE(second.path, file.path);
  std::uint32_t x = 0, n = 0;
  while (reader.read(&x, sizeof x)) ASSERT_EQ(x, n++);
  EXPECT_EQ(n, 10000u);
}

TEST(ScratchFolder, ARecordCutShortIsAnError) {
  testing::TempDir dir;
  ScratchFolder scratch(dir.dir());
  ScratchWriter writer(scratch, "write");
  writer.write("abcdef", 6);
  ScratchReader reader(scratch, writer.finish(), "read");
  char record[4];
  EXPECT_TRUE(reader.read(record, 4));
  EXPECT_THROW(reader.read(record, 4), IoError);
}

TEST(ScratchFolder, RemovedOnSuccessAndAMissingParentIsAnError) {
  testing::TempDir dir;
  std::string folder;
  {
    ScratchFolder scratch(dir.dir());
    folder = scratch.path();
    ScratchWriter writer(scratch, "w");
    writer.write("x", 1);
    writer.finish();
    EXPECT_EQ(filesIn(folder), 1u);
  }
  EXPECT_FALSE(fs::exists(folder));
  try {
    ScratchFolder scratch(dir.path("missing/deeper"));
    FAIL() << "a scratch folder under a missing folder";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("missing/deeper"), std::string::npos) << e.what();
  }
}

TEST(ScratchFolder, RemovedOnSigint) {
  testing::TempDir dir;
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    installInterruptCleanup();
    ScratchFolder scratch(dir.dir());
    for (int i = 0; i < 3; ++i) {
      ScratchWriter writer(scratch, "w");
      writer.write("abc", 3);
      writer.finish();
    }
    ScratchWriter open(scratch, "w");  // a file still being written
    open.write("abc", 3);
    raise(SIGINT);
    _exit(0);  // not reached: the handler exits with 130
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  EXPECT_EQ(filesIn(dir.dir()), 0u) << "the scratch folder and its files are gone";
}

}  // namespace
}  // namespace seamvox
