#include "io/files.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <stdexcept>

extern char** environ;

namespace lash {

namespace {

std::string errno_text(int err) { return std::strerror(err); }

/// write(2) until done; returns 0 or the errno of the failure (a short write followed by a
/// failing one reports the failure). `written` receives the bytes that did reach the file.
int write_all(int fd, const char* data, std::size_t n, std::size_t* written = nullptr) {
  std::size_t done = 0;
  int err = 0;
  while (done < n) {
    const ssize_t w = ::write(fd, data + done, n - done);
    if (w < 0) {
      if (errno == EINTR) continue;
      err = errno;
      break;
    }
    if (w == 0) {
      err = EIO;
      break;
    }
    done += static_cast<std::size_t>(w);
  }
  if (written) *written = done;
  return err;
}

/// fsync of the folder holding `path`, so a rename survives a crash of the machine (best effort:
/// some file systems refuse to open folders for it).
void sync_parent(const std::string& path) {
  std::string dir = std::filesystem::path(path).parent_path().string();
  if (dir.empty()) dir = ".";
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

}  // namespace

IoError::IoError(const std::string& path, const std::string& what, int error_number)
    : std::runtime_error(path + ": " + what), path_(path), error_number_(error_number) {}

void write_file_atomic(const std::string& path, std::string_view text) {
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int err = errno;
    throw IoError(path, "cannot write: " + errno_text(err), err);
  }
  int err = write_all(fd, text.data(), text.size());
  if (err == 0 && ::fsync(fd) != 0) err = errno;
  if (::close(fd) != 0 && err == 0) err = errno;
  if (err == 0 && ::rename(tmp.c_str(), path.c_str()) != 0) err = errno;
  if (err != 0) {
    ::unlink(tmp.c_str());
    throw IoError(path, "cannot write: " + errno_text(err), err);
  }
  sync_parent(path);
}

RowFile::RowFile(std::string path) : path_(std::move(path)) {
  fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) throw IoError(path_, "cannot write: " + errno_text(errno));
  buffer_.reserve(1 << 16);
}

RowFile& RowFile::operator=(RowFile&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) ::close(fd_);
    path_ = std::move(o.path_);
    fd_ = o.fd_;
    buffer_ = std::move(o.buffer_);
    committed_ = o.committed_;
    committed_rows_ = o.committed_rows_;
    o.fd_ = -1;
  }
  return *this;
}

RowFile::~RowFile() {
  if (fd_ >= 0) ::close(fd_);  // only after an exception: close() reports errors
}

void RowFile::append(std::string_view rows) {
  buffer_.append(rows);
  if (buffer_.size() >= (1u << 16)) flush();
}

void RowFile::flush() {
  if (fd_ < 0 || buffer_.empty()) return;
  std::size_t written = 0;
  const int err = write_all(fd_, buffer_.data(), buffer_.size(), &written);
  if (err != 0) {
    // Back to the last whole row that reached the file: a reader never sees half a row, and the
    // file keeps every row that fitted.
    const std::size_t last = written > 0 ? buffer_.rfind('\n', written - 1) : std::string::npos;
    const std::size_t keep = last == std::string::npos ? 0 : last + 1;
    if (::ftruncate(fd_, committed_ + static_cast<long long>(keep)) == 0) {
      committed_ += static_cast<long long>(keep);
      committed_rows_ += std::count(buffer_.begin(), buffer_.begin() + static_cast<long>(keep), '\n');
    }
    ::lseek(fd_, committed_, SEEK_SET);
    buffer_.clear();
    throw IoError(path_, "write failed after " + std::to_string(committed_) +
                             " bytes: " + errno_text(err), err);
  }
  committed_ += static_cast<long long>(buffer_.size());
  committed_rows_ += std::count(buffer_.begin(), buffer_.end(), '\n');
  buffer_.clear();
}

void RowFile::close() {
  if (fd_ < 0) return;
  try {
    flush();
  } catch (...) {
    abandon();
    throw;
  }
  int err = ::fsync(fd_) != 0 ? errno : 0;
  // fsync is not supported on every target (a pipe, /dev/full): only a real write error counts.
  if (err == EINVAL || err == EROFS) err = 0;
  if (::close(fd_) != 0 && err == 0) err = errno;
  fd_ = -1;
  if (err != 0) throw IoError(path_, "cannot close: " + errno_text(err));
}

void RowFile::abandon() {
  buffer_.clear();
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

long long drop_last_rows(const std::string& path, std::size_t bytes) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) throw IoError(path, "cannot open: " + errno_text(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int err = errno;
    ::close(fd);
    throw IoError(path, "cannot read its size: " + errno_text(err));
  }
  // The whole file is read: it is only done after a disk filled up, once.
  std::string text(static_cast<std::size_t>(st.st_size), '\0');
  std::size_t got = 0;
  while (got < text.size()) {
    const ssize_t n = ::pread(fd, text.data() + got, text.size() - got, static_cast<off_t>(got));
    if (n <= 0) break;
    got += static_cast<std::size_t>(n);
  }
  text.resize(got);
  const std::size_t header_end = text.find('\n');
  std::size_t keep = text.size();
  long long dropped = 0;
  while (header_end != std::string::npos && keep > header_end + 1 && text.size() - keep < bytes) {
    const std::size_t prev = text.rfind('\n', keep - 2);  // the end of the row before the last
    keep = prev == std::string::npos ? 0 : prev + 1;
    ++dropped;
  }
  const int rc = ::ftruncate(fd, static_cast<off_t>(keep));
  const int err = rc != 0 ? errno : 0;
  ::close(fd);
  if (rc != 0) throw IoError(path, "cannot shorten: " + errno_text(err));
  return dropped;
}

double last_row_time(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) return std::nan("");
  struct stat st {};
  std::string tail;  // the file's end, read back in blocks until it holds two line ends
  off_t end = ::fstat(fd, &st) == 0 ? st.st_size : 0;
  constexpr off_t kBlock = 1 << 16;
  while (end > 0 && std::count(tail.begin(), tail.end(), '\n') < 2) {
    const off_t n = std::min(end, kBlock);
    std::string block(static_cast<std::size_t>(n), '\0');
    if (::pread(fd, block.data(), block.size(), end - n) != static_cast<ssize_t>(n)) break;
    tail.insert(0, block);
    end -= n;
  }
  ::close(fd);
  // Rows end in '\n'; the last one starts after the line end before it. Its start must not be
  // the file's start (that row is the header).
  if (tail.size() < 2 || tail.back() != '\n') return std::nan("");
  const std::size_t prev = tail.rfind('\n', tail.size() - 2);
  if (prev == std::string::npos) return std::nan("");
  const char* first = tail.c_str() + prev + 1;
  char* stop = nullptr;
  const double t = std::strtod(first, &stop);
  return stop != first && (*stop == ',' || *stop == '\n') ? t : std::nan("");
}

FolderLock::FolderLock(const std::string& folder) {
  std::error_code ec;
  // A folder named by an existing file is a mistaken option (exit 2), not a failed write.
  if (std::filesystem::exists(folder, ec) && !std::filesystem::is_directory(folder, ec))
    throw std::invalid_argument(folder + ": exists and is not a folder; name a folder (it is "
                                "created if missing)");
  std::filesystem::create_directories(folder, ec);
  // So is a path through a file (afile/sub): nothing was written, the option names no folder.
  if (ec == std::errc::not_a_directory)
    throw std::invalid_argument(folder + ": a part of this path is a file, not a folder; name a "
                                "folder (it is created if missing)");
  if (ec) throw IoError(folder, "cannot create the output folder: " + ec.message());
  const std::string path = folder + "/.lash.lock";
  // O_NOFOLLOW: a planted symbolic link must not make the pid overwrite another file.
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (fd_ < 0)
    throw IoError(path, errno == ELOOP ? std::string("is a symbolic link, not a lock file of lash; "
                                                     "remove it")
                                       : "cannot create the lock file: " + errno_text(errno));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    char pid[32] = {};
    const ssize_t n = ::pread(fd_, pid, sizeof pid - 1, 0);
    ::close(fd_);
    fd_ = -1;
    if (err == EWOULDBLOCK) {
      std::string who = n > 0 ? std::string(pid, static_cast<std::size_t>(n)) : std::string();
      while (!who.empty() && (who.back() == '\n' || who.back() == ' ')) who.pop_back();
      // The holder may be this process (Python: another thread's run or sweep into the folder).
      const bool here = who == std::to_string(::getpid());
      throw std::invalid_argument(
          "output folder '" + folder + "' is in use by " +
          (here ? "another run of this process (process " + who + ")"
                : "another lash" + (who.empty() ? std::string() : " (process " + who + ")")) +
          "; wait for it to finish or choose another folder");
    }
    throw IoError(path, "cannot lock: " + errno_text(err));
  }
  const std::string me = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd_, 0) == 0) (void)!::pwrite(fd_, me.data(), me.size(), 0);
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock; the file stays (removing it would race)
}

void remove_earlier_output(const std::string& path, const std::string& marker, bool check_only) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::symlink_status(path, ec);
  if (ec || st.type() == fs::file_type::not_found) return;
  if (st.type() == fs::file_type::regular || st.type() == fs::file_type::symlink) {
    if (check_only) return;
    if (!fs::remove(path, ec) && ec) throw IoError(path, "cannot remove the earlier run's file: " + ec.message());
    return;
  }
  // figures/ from a lash older than the mark is recognised by the figures.log written beside it.
  const bool legacy_figures =
      marker == kFiguresMarker &&
      fs::symlink_status(fs::path(path).parent_path() / "figures.log", ec).type() ==
          fs::file_type::regular;
  if (st.type() == fs::file_type::directory && !marker.empty() &&
      (legacy_figures ||
       fs::symlink_status(path + "/" + marker, ec).type() == fs::file_type::regular)) {
    if (check_only) return;
    fs::remove_all(path, ec);
    if (ec) throw IoError(path, "cannot remove the earlier run's folder: " + ec.message());
    return;
  }
  throw std::invalid_argument(path + ": " +
                              (st.type() == fs::file_type::directory ? "a folder"
                               : st.type() == fs::file_type::fifo    ? "a named pipe"
                               : st.type() == fs::file_type::socket  ? "a socket"
                                                                     : "a device or special file") +
                              " that lash did not write is in the way; it is left alone: move it "
                              "or choose another output folder");
}

std::string read_input_file(const std::string& path, std::size_t max_bytes) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw IoError(path, "cannot open: " + errno_text(errno));
  if (!S_ISREG(st.st_mode))
    throw std::invalid_argument(path + ": not a regular file (expected a text file)");
  if (static_cast<std::size_t>(st.st_size) > max_bytes)
    throw std::invalid_argument(path + ": " + std::to_string(st.st_size) +
                                " bytes, more than the " + std::to_string(max_bytes) +
                                " bytes an input file may have");
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw IoError(path, "cannot open: " + errno_text(errno));
  std::string text;
  char buf[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      throw IoError(path, "cannot read: " + errno_text(err));
    }
    if (n == 0) break;
    text.append(buf, static_cast<std::size_t>(n));
    if (text.size() > max_bytes) {  // grew while being read
      ::close(fd);
      throw std::invalid_argument(path + ": more than the " + std::to_string(max_bytes) +
                                  " bytes an input file may have");
    }
  }
  ::close(fd);
  return text;
}

int run_program(const std::vector<std::string>& argv, const std::string& log_path,
                const std::atomic<int>* interrupt) {
  if (argv.empty()) return -1;
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log_path.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = ::posix_spawn(&pid, argv[0].c_str(), &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) return -1;
  int status = 0;
  if (interrupt) {
    // Polled every 10 ms: the signal handler only stores the signal.
    const int kill_ticks = static_cast<int>(kKillGraceSeconds * 100);
    int ticks = -1;  // since SIGTERM was sent; −1 before
    for (;;) {
      const pid_t w = ::waitpid(pid, &status, WNOHANG);
      if (w == pid) break;
      if (w < 0 && errno != EINTR) return -1;
      if (ticks < 0 && interrupt->load() != 0) {
        ::kill(pid, SIGTERM);
        ticks = 0;
      } else if (ticks >= 0 && ++ticks == kill_ticks) {
        ::kill(pid, SIGKILL);
      }
      const struct timespec tick {0, 10'000'000};
      ::nanosleep(&tick, nullptr);
    }
  } else {
    while (::waitpid(pid, &status, 0) < 0)
      if (errno != EINTR) return -1;
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

std::string folder_name(std::string folder) {
  while (folder.size() > 1 && folder.back() == '/') folder.pop_back();
  return folder;
}

}  // namespace lash
