#pragma once
/// @file files.hpp
/// File-system primitives that never report success for a failed write: atomic whole-file
/// writes, an append-only row file that keeps whole rows on a failed write, a run folder owned
/// by one process, bounded reads of input files, and helper programs started without a shell.
#include <atomic>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace lash {

/// A failed read or write, with the path and the system's reason ("No space left on device").
class IoError : public std::runtime_error {
 public:
  IoError(const std::string& path, const std::string& what, int error_number = 0);
  const std::string& path() const { return path_; }
  /// The system's errno behind it (ENOSPC, EFBIG, ...), 0 if none.
  int error_number() const { return error_number_; }

 private:
  std::string path_;
  int error_number_ = 0;
};

/// Writes `text` to `path` atomically: a temporary file beside it, written, fsync'ed and renamed
/// over `path`. On failure `path` is untouched (an earlier version stays, or none) and the
/// temporary file is removed. Throws IoError.
void write_file_atomic(const std::string& path, std::string_view text);

/// An output file written in whole rows. Rows are buffered and handed to the kernel in whole
/// rows, so a killed process leaves only whole rows; a failed or short write (full disk, file
/// size limit) truncates the file back to its last whole row and throws IoError.
class RowFile {
 public:
  RowFile() = default;
  /// Creates or truncates `path`. Throws IoError.
  explicit RowFile(std::string path);
  RowFile(const RowFile&) = delete;
  RowFile& operator=(const RowFile&) = delete;
  RowFile(RowFile&& o) noexcept { *this = std::move(o); }
  RowFile& operator=(RowFile&& o) noexcept;
  ~RowFile();

  /// Appends one or more whole rows (ending in '\n'); written out when the buffer is full.
  void append(std::string_view rows);
  /// Writes the buffered rows. Throws IoError.
  void flush();
  /// Flushes, fsyncs and closes. Throws IoError. Idempotent.
  void close();
  /// Closes without writing what is buffered (after an error).
  void abandon();
  const std::string& path() const { return path_; }
  bool is_open() const { return fd_ >= 0; }
  /// Rows (lines) on disk.
  long long rows_written() const { return committed_rows_; }

 private:
  std::string path_;
  int fd_ = -1;
  std::string buffer_;
  long long committed_ = 0;       ///< bytes of whole rows on disk
  long long committed_rows_ = 0;  ///< lines in them
};

/// Removes whole rows from the end of the row file at `path` (never its first row, the header)
/// until at least `bytes` are freed or only the header is left. Returns the rows removed. For a
/// full disk: room for the summary that says what the rows are. Throws IoError.
long long drop_last_rows(const std::string& path, std::size_t bytes);

/// The first field of the last whole row of the row file at `path` (a time series' time), read
/// from the end; NaN when the file has no row after its header or cannot be read.
double last_row_time(const std::string& path);

/// Owns a run folder while a command writes into it: an exclusive lock on FOLDER/.lash.lock
/// (flock, released when the process ends, however it ends). A second `lash` writing into the
/// same folder is refused instead of mixing its rows with the first one's.
class FolderLock {
 public:
  /// Creates `folder` if needed and locks it. Throws IoError when it cannot be created, and
  /// std::invalid_argument when it names a file, or naming the other process when another run
  /// holds the lock.
  explicit FolderLock(const std::string& folder);
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;
  ~FolderLock();

 private:
  int fd_ = -1;
};

/// Removes what an earlier run left at `path` before a new one writes there: a file or a symbolic
/// link (never followed); a folder only when it holds `marker` (a file lash put there to say the
/// folder is its own, e.g. figures/.lash-figures; a figures/ folder of an older lash, without the
/// mark, is recognised by the figures.log beside it). Anything else — a user's folder of the same
/// name, a device, a FIFO — is left alone and reported with std::invalid_argument, so no run
/// deletes what it did not write; IoError when removing fails. Nothing there: nothing to do.
/// `check_only`: throw as it would, remove nothing (to check a whole folder before changing it).
void remove_earlier_output(const std::string& path, const std::string& marker = "",
                           bool check_only = false);

/// The file that marks a figures/ folder as written by lash.
constexpr const char* kFiguresMarker = ".lash-figures";

/// Reads an input file (model, state, summary) whole. Refuses what is not a regular file
/// (a directory, /dev/zero, a FIFO) and files larger than `max_bytes`, with std::invalid_argument
/// naming the path; throws IoError when it cannot be read.
std::string read_input_file(const std::string& path, std::size_t max_bytes);

/// A folder's name as messages print it and paths are joined to it: `out/`, `out//` → `out`
/// (the root `/` stays). Applied to every folder given on the command line, so no message says
/// `out//summary.json`.
std::string folder_name(std::string folder);

/// Largest model file read (bytes): far above any mechanism's description.
constexpr std::size_t kMaxModelFileBytes = 16u << 20;

/// Runs `argv[0]` (a path) with arguments `argv`, no shell involved, its stdout and stderr into
/// `log_path`, and waits for it. Returns its exit status (128 + signal if it was killed), or -1
/// when it could not be started. With `interrupt`: once it is non-zero (a signal asked lash to
/// stop), the program gets SIGTERM at once (SIGKILL if still there after kKillGraceSeconds), so
/// no helper goes on writing into a folder lash has given up.
int run_program(const std::vector<std::string>& argv, const std::string& log_path,
                const std::atomic<int>* interrupt = nullptr);

/// How long a helper program stopped by run_program's interrupt may take to end (seconds).
constexpr double kKillGraceSeconds = 2.0;

}  // namespace lash
