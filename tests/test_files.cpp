// io/files.hpp: writes that fail say so and leave whole rows, atomic replacement, folder locks,
// bounded input reads, helper programs without a shell.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <string>

#include "io/files.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

namespace {

fs::path scratch(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("lash_files_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

}  // namespace

TEST(Files, RowFileOnAFullDeviceThrowsWithTheReason) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  lash::RowFile f("/dev/full");
  f.append("a,b\n");
  try {
    f.flush();
    FAIL() << "a write to /dev/full succeeded";
  } catch (const lash::IoError& e) {
    EXPECT_EQ(e.path(), "/dev/full");
    EXPECT_NE(std::string(e.what()).find("No space left on device"), std::string::npos) << e.what();
  }
  EXPECT_EQ(f.rows_written(), 0);
}

TEST(Files, RowFilePastTheSizeLimitKeepsOnlyWholeRows) {
  // A child process with a 4 KiB file-size limit (and SIGXFSZ ignored, as `lash` does) writes
  // 60-byte rows until a write fails; the file must end on a whole row and hold as many rows
  // as rows_written() says.
  const fs::path dir = scratch("limit");
  const fs::path file = dir / "rows.csv";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    std::signal(SIGXFSZ, SIG_IGN);
    rlimit lim{4096, 4096};
    setrlimit(RLIMIT_FSIZE, &lim);
    lash::RowFile f(file.string());
    const std::string row = std::string(59, 'x') + "\n";
    try {
      for (int i = 0; i < 1000; ++i) {
        f.append(row);
        if (i % 7 == 0) f.flush();  // failures land mid-buffer, not only at row boundaries
      }
      f.close();
    } catch (const lash::IoError& e) {
      std::ofstream((dir / "rows_written").string()) << f.rows_written();
      _exit(std::string(e.what()).find("File too large") != std::string::npos ? 3 : 4);
    }
    _exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  ASSERT_EQ(WEXITSTATUS(status), 3) << "expected a reported EFBIG";
  const std::string text = lash::test::read_file(file.string());
  ASSERT_FALSE(text.empty());
  EXPECT_LE(text.size(), 4096u);
  EXPECT_EQ(text.back(), '\n');
  EXPECT_EQ(text.size() % 60, 0u) << "a row was cut";
  long long rows = -1;
  std::ifstream(dir / "rows_written") >> rows;
  EXPECT_EQ(rows, static_cast<long long>(text.size() / 60));
  fs::remove_all(dir);
}

TEST(Files, AtomicWriteReplacesWholeOrLeavesTheOldFile) {
  const fs::path dir = scratch("atomic");
  const std::string path = (dir / "summary.json").string();
  lash::write_file_atomic(path, "old\n");
  lash::write_file_atomic(path, "new\n");
  EXPECT_EQ(lash::test::read_file(path), "new\n");
  // A folder that does not exist: an IoError naming the file, nothing left behind.
  EXPECT_THROW(lash::write_file_atomic((dir / "missing" / "x.json").string(), "x"), lash::IoError);
  // No temporary files stay.
  int n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  EXPECT_EQ(n, 1);
  fs::remove_all(dir);
}

TEST(Files, AFolderLockRefusesASecondOwnerAndIsReleasedWithIt) {
  const fs::path dir = scratch("lock");
  {
    lash::FolderLock first((dir / "run").string());
    // flock locks belong to the open file description: a second open in this process conflicts
    // like another process would.
    try {
      lash::FolderLock second((dir / "run").string());
      FAIL() << "two owners of one folder";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("in use by another run of this process (process " +
                                           std::to_string(getpid()) + "); wait for it to finish "
                                           "or choose another folder"),
                std::string::npos)
          << e.what();
    }
  }
  EXPECT_NO_THROW(lash::FolderLock again((dir / "run").string()));
  // A planted symbolic link is refused, and its target keeps its text.
  fs::create_directories(dir / "linked");
  std::ofstream(dir / "precious.txt") << "precious";
  fs::create_symlink(dir / "precious.txt", dir / "linked" / ".lash.lock");
  EXPECT_THROW(lash::FolderLock((dir / "linked").string()), lash::IoError);
  EXPECT_EQ(lash::test::read_file((dir / "precious.txt").string()), "precious");
  fs::remove_all(dir);
}

TEST(Files, InputFilesMustBeRegularAndBounded) {
  const fs::path dir = scratch("input");
  EXPECT_THROW(lash::read_input_file("/dev/zero", 1024), std::invalid_argument);
  EXPECT_THROW(lash::read_input_file(dir.string(), 1024), std::invalid_argument);
  std::ofstream(dir / "big.yaml") << std::string(2000, 'a');
  try {
    lash::read_input_file((dir / "big.yaml").string(), 1024);
    FAIL() << "read past the limit";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("2000 bytes, more than the 1024"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(lash::read_input_file((dir / "big.yaml").string(), 4096).size(), 2000u);
  EXPECT_THROW(lash::read_input_file((dir / "none.yaml").string(), 4096), lash::IoError);
  fs::remove_all(dir);
}

TEST(Files, HelperProgramsGetTheirArgumentsVerbatim) {
  // An argument full of shell syntax reaches the program as one argument and runs nothing.
  const fs::path dir = scratch("spawn");
  const std::string tricky = (dir / "x';touch PWNED;'$(touch PWNED2) \"q\"").string();
  const int rc = lash::run_program({"/usr/bin/printf", "%s", tricky}, (dir / "log").string());
  EXPECT_EQ(rc, 0);
  EXPECT_EQ(lash::test::read_file((dir / "log").string()), tricky);
  EXPECT_FALSE(fs::exists("PWNED"));
  EXPECT_FALSE(fs::exists("PWNED2"));
  EXPECT_FALSE(fs::exists(dir / "PWNED"));
  // Not started (glibc reports it from posix_spawn) or started and failed to exec.
  const int missing = lash::run_program({"/nonexistent/program"}, (dir / "log2").string());
  EXPECT_TRUE(missing == -1 || missing == 127) << missing;
  fs::remove_all(dir);
}
