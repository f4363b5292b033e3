#include "io/hdf5_series.hpp"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "io/files.hpp"

#ifdef LASH_HDF5
#include <hdf5.h>
#endif

namespace lash {

#ifdef LASH_HDF5

bool hdf5_available() { return true; }

struct Hdf5Series::Handles {
  hid_t file = -1;
  std::vector<hid_t> datasets;
  off_t flushed_size = -1;  ///< the file's size after its last successful flush
  bool failed = false;      ///< a write or flush failed: the file must not be flushed again
};

namespace {

/// A UTF-8 string attribute (units such as "m/s²"), variable-length: what h5py reads as a str
/// (a fixed-length one comes back as bytes).
bool write_string_attribute(hid_t object, const char* name, const std::string& value) {
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, H5T_VARIABLE);
  H5Tset_cset(type, H5T_CSET_UTF8);
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t attr = H5Acreate2(object, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  const char* text = value.c_str();
  const bool ok = attr >= 0 && H5Awrite(attr, type, &text) >= 0;
  if (attr >= 0) H5Aclose(attr);
  H5Sclose(space);
  H5Tclose(type);
  return ok;
}

/// The size of the file `path` (−1 if it cannot be read).
off_t file_size(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 ? st.st_size : -1;
}

std::string reason() {
  return errno != 0 ? std::string("HDF5 write failed: ") + std::strerror(errno)
                    : std::string("HDF5 write failed");
}

}  // namespace

Hdf5Series::Hdf5Series(const std::string& path, const std::vector<ChannelInfo>& channels)
    : path_(path), h_(std::make_unique<Handles>()) {
  // The library's exit handler would flush files still open; every file is closed here, and
  // one whose write failed must not be flushed (abandon).
  H5dont_atexit();
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are reported as IoError, not printed
  errno = 0;
  h_->file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (h_->file < 0) throw IoError(path, "cannot create the HDF5 file");
  std::vector<ChannelInfo> cols = {{"time", "s", "time"}};
  cols.insert(cols.end(), channels.begin(), channels.end());
  const hsize_t dims[1] = {0}, max_dims[1] = {H5S_UNLIMITED}, chunk[1] = {kChunkRows};
  for (const auto& c : cols) {
    const hid_t space = H5Screate_simple(1, dims, max_dims);
    const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(dcpl, 1, chunk);
    // Every chunk is written whole before it is read: no fill values written first (they were
    // 7% of a long run's time, in memset).
    H5Pset_fill_time(dcpl, H5D_FILL_TIME_NEVER);
    const hid_t ds = H5Dcreate2(h_->file, c.name.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT,
                                dcpl, H5P_DEFAULT);
    H5Pclose(dcpl);
    H5Sclose(space);
    if (ds < 0) {
      abandon();
      throw IoError(path, "cannot create the HDF5 dataset '" + c.name + "'");
    }
    h_->datasets.push_back(ds);
    if (!write_string_attribute(ds, "unit", c.unit) ||
        !write_string_attribute(ds, "description", c.description)) {
      abandon();
      throw IoError(path, "cannot write the attributes of '" + c.name + "'");
    }
  }
  columns_.assign(cols.size(), {});
  for (auto& col : columns_) col.reserve(kChunkRows);
  if (H5Fflush(h_->file, H5F_SCOPE_LOCAL) < 0) {
    h_->failed = true;
    const std::string why = reason();
    abandon();
    throw IoError(path, why);
  }
  h_->flushed_size = file_size(path_);
}

Hdf5Series::~Hdf5Series() { abandon(); }

bool Hdf5Series::is_open() const { return h_ && h_->file >= 0; }

void Hdf5Series::append(double t, const double* values) {
  columns_[0].push_back(t);
  for (std::size_t i = 1; i < columns_.size(); ++i) columns_[i].push_back(values[i - 1]);
  if (columns_[0].size() >= kChunkRows) write_buffered();
}

void Hdf5Series::write_buffered() {
  const hsize_t n = columns_[0].size();
  if (n == 0 || !is_open()) return;
  // Room for the chunk first. A write HDF5 starts and cannot finish leaves a file it can no
  // longer open (see abandon), so a chunk that would pass the file-size limit or fill the disk
  // is not started: the file closes as its last flush left it. The need: a whole chunk's
  // doubles (HDF5 allocates the last, partial chunk whole: sized by its rows, the check let a
  // last chunk start that could not finish), a twentieth more for the chunk index and headers,
  // and 64 KiB.
  const double need = 1.05 * 8.0 * static_cast<double>(kChunkRows * columns_.size()) + 65536.0;
  rlimit limit{};
  if (::getrlimit(RLIMIT_FSIZE, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY &&
      static_cast<double>(h_->flushed_size) + need > static_cast<double>(limit.rlim_cur))
    throw IoError(path_, std::string("HDF5 write not started: ") + std::strerror(EFBIG) +
                             " (the next chunk would pass the file-size limit)");
  struct statvfs fs {};
  if (::statvfs(path_.c_str(), &fs) == 0 &&
      static_cast<double>(fs.f_bavail) * static_cast<double>(fs.f_frsize) < need)
    throw IoError(path_, std::string("HDF5 write not started: ") + std::strerror(ENOSPC) +
                             " (no room for the next chunk)");
  errno = 0;
  const hsize_t start[1] = {static_cast<hsize_t>(rows_)}, count[1] = {n};
  const hsize_t extent[1] = {static_cast<hsize_t>(rows_) + n};
  const hid_t mem = H5Screate_simple(1, count, nullptr);
  bool ok = true;
  for (std::size_t i = 0; ok && i < columns_.size(); ++i) {
    const hid_t ds = h_->datasets[i];
    ok = H5Dset_extent(ds, extent) >= 0;
    const hid_t file_space = ok ? H5Dget_space(ds) : -1;
    ok = ok && file_space >= 0 &&
         H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start, nullptr, count, nullptr) >= 0 &&
         H5Dwrite(ds, H5T_NATIVE_DOUBLE, mem, file_space, H5P_DEFAULT, columns_[i].data()) >= 0;
    if (file_space >= 0) H5Sclose(file_space);
  }
  H5Sclose(mem);
  ok = ok && H5Fflush(h_->file, H5F_SCOPE_LOCAL) >= 0;
  if (!ok) {
    h_->failed = true;
    throw IoError(path_, reason());
  }
  h_->flushed_size = file_size(path_);
  rows_ += static_cast<long long>(n);
  last_time_ = columns_[0].back();  // the time column
  for (auto& col : columns_) col.clear();
}

void Hdf5Series::close() {
  if (!is_open()) return;
  try {
    write_buffered();
  } catch (const IoError&) {
    abandon();  // the chunks flushed before stay, readable
    throw;
  }
  for (hid_t ds : h_->datasets) H5Dclose(ds);
  h_->datasets.clear();
  const herr_t rc = H5Fclose(h_->file);
  h_->file = -1;
  if (rc < 0) throw IoError(path_, reason());
  // On the disk, as RowFile::close makes the CSV: HDF5 itself never fsyncs.
  const int fd = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
  const bool synced = fd >= 0 && ::fsync(fd) == 0;
  if (fd >= 0) ::close(fd);
  if (!synced) throw IoError(path_, std::string("fsync failed: ") + std::strerror(errno));
}

void Hdf5Series::abandon() {
  if (!is_open()) return;
  if (h_->failed) {
    // HDF5 flushes a file's dirty metadata when it closes it. After a failed write (a full disk,
    // a file-size limit) that flush fails too, or writes a superblock that counts space never
    // written, and the file no longer opens; and a file left open crashed the library's exit
    // handler. So the file's descriptor is pointed at /dev/null before closing (the close
    // writes nothing), and the file is cut back to its size at its last successful flush:
    // the chunks written before the failure, as consistent as that flush left them.
    void* handle = nullptr;
    if (H5Fget_vfd_handle(h_->file, H5P_DEFAULT, &handle) >= 0 && handle) {
      const int null = ::open("/dev/null", O_RDWR | O_CLOEXEC);
      if (null >= 0) {
        ::dup2(null, *static_cast<int*>(handle));
        ::close(null);
      }
    }
  }
  for (hid_t ds : h_->datasets) H5Dclose(ds);
  h_->datasets.clear();
  H5Fclose(h_->file);
  h_->file = -1;
  if (h_->failed && h_->flushed_size >= 0) (void)::truncate(path_.c_str(), h_->flushed_size);
}

struct Hdf5Rows::Handles {
  hid_t file = -1;
  std::vector<hid_t> datasets;
  ~Handles() {
    for (hid_t ds : datasets) H5Dclose(ds);
    if (file >= 0) H5Fclose(file);
  }
};

Hdf5Rows::Hdf5Rows(const std::string& path, const std::vector<std::string>& columns, long long rows)
    : path_(path), h_(std::make_unique<Handles>()), rows_(rows) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  h_->file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (h_->file < 0)
    throw std::invalid_argument(path + ": damaged (not a readable HDF5 file); run the model again");
  std::vector<std::string> names = {"time"};
  names.insert(names.end(), columns.begin(), columns.end());
  for (const auto& name : names) {
    const hid_t ds = H5Lexists(h_->file, name.c_str(), H5P_DEFAULT) > 0
                         ? H5Dopen2(h_->file, name.c_str(), H5P_DEFAULT)
                         : -1;
    if (ds < 0)
      throw std::invalid_argument(path + ": no dataset '" + name + "' (summary.json lists it): "
                                  "edited after the run? Run the model again");
    h_->datasets.push_back(ds);
    const hid_t space = H5Dget_space(ds), type = H5Dget_type(ds);
    hsize_t n = 0;
    const bool one_d = H5Sget_simple_extent_ndims(space) == 1 &&
                       H5Sget_simple_extent_dims(space, &n, nullptr) == 1;
    const bool doubles = H5Tget_class(type) == H5T_FLOAT && H5Tget_size(type) == 8;
    H5Tclose(type);
    H5Sclose(space);
    if (!one_d || !doubles)
      throw std::invalid_argument(path + ": dataset '" + name + "' is not a column of doubles");
    if (static_cast<long long>(n) != rows)
      throw std::invalid_argument(path + ": dataset '" + name + "' has " + std::to_string(n) +
                                  " rows, summary.json says " + std::to_string(rows) +
                                  ": cut or edited after the run");
  }
  chunk_.assign(names.size(), {});
}

Hdf5Rows::~Hdf5Rows() = default;

void Hdf5Rows::read_chunk() {
  const long long n = std::min<long long>(Hdf5Series::kChunkRows, rows_ - start_);
  const hsize_t start[1] = {static_cast<hsize_t>(start_)}, count[1] = {static_cast<hsize_t>(n)};
  const hid_t mem = H5Screate_simple(1, count, nullptr);
  bool ok = mem >= 0;
  for (std::size_t i = 0; ok && i < h_->datasets.size(); ++i) {
    chunk_[i].resize(static_cast<std::size_t>(n));
    const hid_t file_space = H5Dget_space(h_->datasets[i]);
    ok = file_space >= 0 &&
         H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start, nullptr, count, nullptr) >= 0 &&
         H5Dread(h_->datasets[i], H5T_NATIVE_DOUBLE, mem, file_space, H5P_DEFAULT,
                 chunk_[i].data()) >= 0;
    if (file_space >= 0) H5Sclose(file_space);
  }
  if (mem >= 0) H5Sclose(mem);
  if (!ok) throw IoError(path_, "cannot read rows " + std::to_string(start_ + 1) + " to " +
                                    std::to_string(start_ + n));
  k_ = 0;
}

bool Hdf5Rows::next(double& t, double* values) {
  if (k_ >= chunk_[0].size()) {
    if (start_ + static_cast<long long>(chunk_[0].size()) >= rows_) return false;
    start_ += static_cast<long long>(chunk_[0].size());
    read_chunk();
  }
  t = chunk_[0][k_];
  for (std::size_t i = 1; i < chunk_.size(); ++i) values[i - 1] = chunk_[i][k_];
  ++k_;
  return true;
}

#else  // no HDF5 in this build

bool hdf5_available() { return false; }
struct Hdf5Series::Handles {};
Hdf5Series::Hdf5Series(const std::string& path, const std::vector<ChannelInfo>&) : path_(path) {
  throw std::invalid_argument("this lash was built without HDF5 (Debian's libhdf5-dev); "
                              "use the CSV format");
}
Hdf5Series::~Hdf5Series() = default;
bool Hdf5Series::is_open() const { return false; }
void Hdf5Series::append(double, const double*) {}
void Hdf5Series::write_buffered() {}
void Hdf5Series::close() {}
void Hdf5Series::abandon() {}

struct Hdf5Rows::Handles {};
Hdf5Rows::Hdf5Rows(const std::string& path, const std::vector<std::string>&, long long) : path_(path) {
  throw std::invalid_argument(path + ": this lash was built without HDF5 (Debian's libhdf5-dev) "
                              "and cannot read it");
}
Hdf5Rows::~Hdf5Rows() = default;
bool Hdf5Rows::next(double&, double*) { return false; }
void Hdf5Rows::read_chunk() {}

#endif

}  // namespace lash
