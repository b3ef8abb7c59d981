#include "delta/io/atomic_file.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "delta/core/error.h"
#include "delta/io/mesh_io.h"
#include "delta/io/vtk.h"
#include "delta/mesh/primitives.h"

#include "io/file_size_limit.h"
#include "io/test_files.h"

namespace delta::io {
namespace {

namespace fs = std::filesystem;

/// A fresh folder in the temporary folder, removed with what is in it.
struct Folder {
  explicit Folder(const std::string& name)
      : path(fs::temp_directory_path() /
             ("delta_atomic_" + std::to_string(::getpid()) + "_" + name)) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~Folder() { fs::remove_all(path); }
  Folder(const Folder&) = delete;
  Folder& operator=(const Folder&) = delete;
  fs::path path;
};

std::string contentOf(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

void put(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

/// Runs `write`, which must throw delta::Error whose message contains every one of `needles`.
template <typename Write>
void expectError(const Write& write, std::initializer_list<std::string> needles) {
  try {
    write();
    ADD_FAILURE() << "no delta::Error";
  } catch (const Error& error) {
    for (const std::string& needle : needles)
      EXPECT_NE(std::string(error.what()).find(needle), std::string::npos)
          << "'" << needle << "' not in: " << error.what();
  }
}

TEST(AtomicFile, WritesTheFileWholeAndLeavesNoTemporaryFile) {
  Folder folder("whole");
  const fs::path path = folder.path / "out.csv";
  AtomicFile file(path);
  file.write("a,b\n");
  EXPECT_FALSE(fs::exists(path)) << "visible before commit()";
  std::string rows;
  for (int i = 0; i < 100000; ++i)
    rows += std::to_string(i) + "," + std::to_string(2 * i) + "\n";
  file.write(rows);  // larger than the buffer: written through
  file.write("end\n");
  file.commit();
  EXPECT_EQ(contentOf(path), "a,b\n" + rows + "end\n");
  EXPECT_EQ(namesIn(folder.path), std::vector<std::string>{"out.csv"});
}

TEST(AtomicFile, TemporaryFilesBeingWrittenAreDiscardedForASignal) {
  // What a SIGINT/SIGTERM handler calls before the process ends (the `delta` tool's): every
  // temporary file still being written goes, committed files and earlier ones stay. More files
  // than it tracks at once: those beyond are left to their destructors.
  Folder folder("signal");
  const fs::path kept = folder.path / "kept.csv";
  put(folder.path / "previous.csv", "old");
  writeFileAtomically(kept, "done");
  {
    std::vector<std::unique_ptr<AtomicFile>> open;
    for (int i = 0; i < kTrackedTemporaryFiles + 3; ++i) {
      open.push_back(std::make_unique<AtomicFile>(folder.path / ("f" + std::to_string(i))));
      open.back()->write("part");
    }
    ASSERT_EQ(namesIn(folder.path).size(), 2u + kTrackedTemporaryFiles + 3);
    open.erase(open.begin(), open.begin() + 3);         // their slots are free again
    AtomicFile previous(folder.path / "previous.csv");  // takes one of them
    previous.write("new");
    discardTemporaryFiles();
    // The 61 tracked ones left and `previous`'s went; the three made while every slot was
    // taken are left to their destructors.
    EXPECT_EQ(namesIn(folder.path).size(), 2u + 3u);
    expectError([&previous] { previous.commit(); }, {"previous.csv"});
    EXPECT_EQ(contentOf(folder.path / "previous.csv"), "old");
  }
  EXPECT_EQ(namesIn(folder.path), (std::vector<std::string>{"kept.csv", "previous.csv"}));
  EXPECT_EQ(contentOf(kept), "done");
}

TEST(AtomicFile, ReplacesAFileAndKeepsItsPermissions) {
  Folder folder("permissions");
  const fs::path path = folder.path / "out.vtp";
  put(path, "old");
  ::chmod(path.c_str(), 0640);
  writeFileAtomically(path, "new");
  EXPECT_EQ(contentOf(path), "new");
  struct stat status {};
  ASSERT_EQ(::stat(path.c_str(), &status), 0);
  EXPECT_EQ(status.st_mode & 07777, 0640u);
  // A new file: 0666 less the umask, as a plain open would make it (not mkstemp's 0600).
  const mode_t mask = ::umask(022);
  const fs::path fresh = folder.path / "fresh.csv";
  writeFileAtomically(fresh, "x");
  ::umask(mask);
  ASSERT_EQ(::stat(fresh.c_str(), &status), 0);
  EXPECT_EQ(status.st_mode & 07777, 0644u);
}

TEST(AtomicFile, AFailedWriteLeavesThePreviousFileAndNoTemporaryFile) {
  Folder folder("full");
  const fs::path path = folder.path / "out.csv";
  put(path, "previous\n");
  const std::string big(3 << 20, 'x');   // written through the buffer
  const std::string small(100000, 'y');  // buffered: fails at commit()
  {
    const test::FileSizeLimit limit(64 * 1024);
    expectError([&] { writeFileAtomically(path, big); }, {path.string(), "File too large"});
    expectError([&] { writeFileAtomically(path, small); }, {path.string(), "File too large"});
    expectError(
        [&] {
          AtomicFile file(path);
          for (int i = 0; i < 100; ++i)
            file.write(small);
          file.commit();
        },
        {path.string(), "File too large"});
  }
  EXPECT_EQ(contentOf(path), "previous\n");
  EXPECT_EQ(namesIn(folder.path), std::vector<std::string>{"out.csv"});
}

TEST(AtomicFile, AFileNotCommittedIsNotWritten) {
  Folder folder("abandoned");
  const fs::path path = folder.path / "out.csv";
  put(path, "previous\n");
  {
    AtomicFile file(path);
    file.write("half a fi");
  }  // e.g. an exception between the writes
  EXPECT_EQ(contentOf(path), "previous\n");
  EXPECT_EQ(namesIn(folder.path), std::vector<std::string>{"out.csv"});
}

TEST(AtomicFile, ASymlinkIsKeptAndItsTargetReplaced) {
  Folder folder("symlink");
  fs::create_directories(folder.path / "data");
  const fs::path target = folder.path / "data" / "real.csv";
  put(target, "previous\n");
  const fs::path link = folder.path / "out.csv";
  fs::create_symlink(fs::path("data") / "real.csv", link);  // relative to the link's folder
  const fs::path chained = folder.path / "chained.csv";
  fs::create_symlink("out.csv", chained);
  writeFileAtomically(chained, "new\n");
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_TRUE(fs::is_symlink(chained));
  EXPECT_EQ(fs::read_symlink(link), fs::path("data") / "real.csv");
  EXPECT_EQ(contentOf(target), "new\n");
  EXPECT_EQ(namesIn(folder.path / "data"), std::vector<std::string>{"real.csv"});
  // A link to a file not there yet makes the file.
  const fs::path dangling = folder.path / "dangling.csv";
  fs::create_symlink(fs::path("data") / "later.csv", dangling);
  writeFileAtomically(dangling, "made\n");
  EXPECT_TRUE(fs::is_symlink(dangling));
  EXPECT_EQ(contentOf(folder.path / "data" / "later.csv"), "made\n");
  // A failed write through a link leaves link and target as they were.
  {
    const test::FileSizeLimit limit(1024);
    expectError([&] { writeFileAtomically(link, std::string(1 << 21, 'z')); },
                {link.string(), "File too large"});
  }
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(contentOf(target), "new\n");
  EXPECT_EQ(namesIn(folder.path / "data"), (std::vector<std::string>{"later.csv", "real.csv"}));
}

TEST(AtomicFile, RefusesWhatItCannotWrite) {
  Folder folder("refused");
  expectError([&] { writeFileAtomically(folder.path, "x"); },
              {folder.path.string(), "it is a folder"});
  const fs::path missing = folder.path / "no_such_folder" / "out.csv";
  expectError([&] { writeFileAtomically(missing, "x"); },
              {missing.string(), "No such file or directory"});
  const fs::path loop = folder.path / "loop.csv";
  fs::create_symlink("loop2.csv", loop);
  fs::create_symlink("loop.csv", folder.path / "loop2.csv");
  expectError([&] { writeFileAtomically(loop, "x"); },
              {loop.string(), "too many levels of symbolic links"});
  expectError([&] { writeFileAtomically("", "x"); }, {"the path is empty"});
}

TEST(AtomicFile, AFileThatMayNotBeWrittenIsRefused) {
  if (::geteuid() == 0) GTEST_SKIP() << "root may write any file";
  Folder folder("read_only");
  const fs::path path = folder.path / "kept.csv";
  put(path, "previous\n");
  ::chmod(path.c_str(), 0444);
  expectError([&] { writeFileAtomically(path, "new"); }, {path.string(), "Permission denied"});
  EXPECT_EQ(contentOf(path), "previous\n");
  EXPECT_EQ(namesIn(folder.path), std::vector<std::string>{"kept.csv"});
}

TEST(AtomicFile, DevicesAreWrittenInPlaceAndFailuresReported) {
  writeFileAtomically("/dev/null", "nothing");
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  expectError([] { writeFileAtomically("/dev/full", "x"); },
              {"cannot write '/dev/full'", "No space left on device"});
  EXPECT_TRUE(fs::is_character_file("/dev/full"));
}

TEST(AtomicFile, AStreamTheProcessHoldsIsWrittenInPlace) {
  // /dev/fd/N (like /dev/stdout) names a file this process holds open: appended to, never
  // replaced (a rename would leave the holder writing to a file no longer there).
  Folder folder("stream");
  const fs::path path = folder.path / "log.txt";
  const int descriptor = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  ASSERT_GE(descriptor, 0);
  ASSERT_EQ(::write(descriptor, "before\n", 7), 7);
  struct stat before {};
  ASSERT_EQ(::fstat(descriptor, &before), 0);
  writeFileAtomically("/dev/fd/" + std::to_string(descriptor), "after\n");
  ::close(descriptor);
  EXPECT_EQ(contentOf(path), "before\nafter\n");
  struct stat after {};
  ASSERT_EQ(::stat(path.c_str(), &after), 0);
  EXPECT_EQ(after.st_ino, before.st_ino);
  EXPECT_EQ(namesIn(folder.path), std::vector<std::string>{"log.txt"});
}

TEST(AtomicFile, ARegularFileUnderDevIsReplacedNotAppendedTo) {
  // Files on the /dev/shm tmpfs are files like any other: a rule on the prefix /dev appended
  // every rewrite to them (two CSVs in one file, a DEM checkpoint that could not be read back).
  // A link elsewhere to /dev/stdout still names a stream.
  const fs::path shm = "/dev/shm";
  std::error_code error;
  if (!fs::is_directory(shm, error) || ::access(shm.c_str(), W_OK) != 0)
    GTEST_SKIP() << "no writable /dev/shm";
  const fs::path path = shm / ("delta_atomic_" + std::to_string(::getpid()) + ".csv");
  writeFileAtomically(path, "first\n");
  writeFileAtomically(path, "second\n");
  EXPECT_EQ(contentOf(path), "second\n");
  fs::remove(path);

  Folder folder("stream_link");
  const fs::path log = folder.path / "log.txt";
  const int descriptor = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  ASSERT_GE(descriptor, 0);
  ASSERT_EQ(::write(descriptor, "before\n", 7), 7);
  const fs::path link = folder.path / "out.csv";
  fs::create_symlink("/proc/self/fd/" + std::to_string(descriptor), link);
  writeFileAtomically(link, "after\n");
  ::close(descriptor);
  EXPECT_EQ(contentOf(log), "before\nafter\n");
  EXPECT_TRUE(fs::is_symlink(link));
}

// Every writer of Δ's library goes through AtomicFile: a full disk is an error, and the previous
// file stays.

TEST(AtomicFileWriters, MeshSaveReportsAFullDevice) {
  const Mesh box = primitives::box();
  Folder folder("save");
  // The format comes from the name: a link named .stl to /dev/full (assimp's own file writing
  // ignored the failure and save returned normally).
  const fs::path full = folder.path / "full.stl";
  fs::create_symlink("/dev/full", full);
  expectError([&] { save(box, full); }, {full.string(), "No space left on device"});
  EXPECT_TRUE(fs::is_character_file("/dev/full"));
  fs::remove(full);
  const fs::path path = folder.path / "box.stl";
  save(box, path);
  const std::string previous = contentOf(path);
  const Mesh sphere = primitives::icosphere(5);
  {
    const test::FileSizeLimit limit(4096);
    expectError([&] { save(sphere, path); }, {path.string(), "File too large"});
  }
  EXPECT_EQ(contentOf(path), previous);
  EXPECT_EQ(namesIn(folder.path), std::vector<std::string>{"box.stl"});
  save(sphere, path);
  EXPECT_EQ(load(path).triangleCount(), sphere.triangleCount());
}

TEST(AtomicFileWriters, VtkWritersReportAFullDevice) {
  const VtkPolyData box = VtkPolyData::fromMesh(primitives::box());
  expectError([&] { writeVtp(box, "/dev/full"); }, {"/dev/full", "No space left on device"});
  const VtkSeriesEntry entry{0.0, "a.vtp"};
  expectError([&] { writePvd({&entry, 1}, "/dev/full"); }, {"/dev/full", "No space left"});
  Folder folder("vtk");
  const fs::path path = folder.path / "box.vtp";
  writeVtp(box, path);
  const std::string previous = contentOf(path);
  {
    const test::FileSizeLimit limit(4096);
    expectError([&] { writeVtp(VtkPolyData::fromMesh(primitives::icosphere(5)), path); },
                {path.string(), "File too large"});
  }
  EXPECT_EQ(contentOf(path), previous);
  EXPECT_EQ(namesIn(folder.path), std::vector<std::string>{"box.vtp"});
}

}  // namespace
}  // namespace delta::io
