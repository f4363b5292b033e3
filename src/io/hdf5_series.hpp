#pragma once
/// @file hdf5_series.hpp
/// A run's time series as HDF5 (timeseries.h5, `lash run --format hdf5`): one 1-D dataset of
/// 64-bit IEEE doubles per column (`time` first, then each channel under its own name, e.g.
/// `slider.x`), each with the string attributes `unit` and `description`. Datasets are chunked
/// and extendible: rows are buffered in memory and appended one chunk at a time, and the file is
/// flushed (H5Fflush) after every chunk, so the rows on disk grow as the run goes and every
/// dataset has the same length after each flush. Built only when HDF5 (Debian's libhdf5-dev,
/// serial) was found; hdf5_available() says whether it was.
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/elements/registry.hpp"

namespace lash {

/// Whether this build can write HDF5.
bool hdf5_available();

class Hdf5Series {
 public:
  /// Rows per chunk (and per append to the file): 4096 doubles = 32 KiB per dataset.
  static constexpr std::size_t kChunkRows = 4096;

  /// Creates (or truncates) `path` with a dataset `time` and one per channel. Throws IoError,
  /// or std::invalid_argument in a build without HDF5.
  Hdf5Series(const std::string& path, const std::vector<ChannelInfo>& channels);
  Hdf5Series(const Hdf5Series&) = delete;
  Hdf5Series& operator=(const Hdf5Series&) = delete;
  ~Hdf5Series();

  /// Appends one row: time and one value per channel, in the constructor's order. Writes a chunk
  /// when kChunkRows rows are buffered. Throws IoError (the file keeps its earlier chunks).
  void append(double t, const double* values);
  /// Writes the buffered rows, flushes and closes. Throws IoError. Idempotent.
  void close();
  /// Closes without writing what is buffered (after an error).
  void abandon();
  bool is_open() const;
  /// Rows in the file as of its last flush.
  long long rows_written() const { return rows_; }
  /// The time of the last row in the file as of its last flush; NaN before the first.
  double last_time() const { return last_time_; }
  const std::string& path() const { return path_; }

 private:
  void write_buffered();

  struct Handles;
  std::string path_;
  std::unique_ptr<Handles> h_;
  std::vector<std::vector<double>> columns_;  ///< buffered rows, column by column
  long long rows_ = 0;
  double last_time_ = std::numeric_limits<double>::quiet_NaN();
};

/// Reads the rows of a timeseries.h5 back, one chunk of every dataset at a time (memory: one
/// chunk per column, whatever the run's length).
class Hdf5Rows {
 public:
  /// Opens `path` read-only and the datasets `time` and `columns` (in that order). Throws
  /// std::invalid_argument naming the file and what is wrong (a dataset missing, not 1-D
  /// doubles, or not `rows` long: cut or edited after the run), or in a build without HDF5.
  Hdf5Rows(const std::string& path, const std::vector<std::string>& columns, long long rows);
  Hdf5Rows(const Hdf5Rows&) = delete;
  Hdf5Rows& operator=(const Hdf5Rows&) = delete;
  ~Hdf5Rows();
  /// The next row: its time and one value per column; false after the last. Throws IoError
  /// when a read fails.
  bool next(double& t, double* values);

 private:
  void read_chunk();

  struct Handles;
  std::string path_;
  std::unique_ptr<Handles> h_;
  std::vector<std::vector<double>> chunk_;  ///< the current chunk, column by column
  long long rows_ = 0, start_ = 0;          ///< rows in the file, first row of the chunk
  std::size_t k_ = 0;                       ///< next row within the chunk
};

}  // namespace lash
