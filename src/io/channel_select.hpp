#pragma once
/// @file channel_select.hpp
/// Which channels a run writes to its time series: glob patterns over the channel names
/// (`lash run --channels 'slider.*,rod_slider.*'`, or `solver.output_channels` in the model,
/// docs/model-format.md §13). `time` is always written and is not a channel here.
#include <cstddef>
#include <string>
#include <vector>

#include "core/elements/registry.hpp"

namespace lash {

/// How a run's time series is written: timeseries.csv (9 significant digits) or timeseries.h5
/// (HDF5, every double as computed).
enum class OutputFormat { csv, hdf5 };

/// What a run writes: the model file's `solver.output_channels` and `solver.output_format`,
/// replaced by `lash run --channels` and `--format`.
struct OutputSettings {
  std::vector<std::string> channels;  ///< glob patterns; empty: all channels
  OutputFormat format = OutputFormat::csv;
};

/// Splits a comma-separated list of patterns ("slider.*, rod_slider.F") into its patterns,
/// spaces around each removed, empty entries dropped.
std::vector<std::string> split_channel_patterns(const std::string& list);

/// Indices into `channels` of the channels that match at least one pattern (shell globs as
/// fnmatch(3): `*`, `?`, `[...]`; `*` also matches dots), in the channels' own order, each once.
/// No patterns: every channel. A `[` that no `]` closes is an error (std::invalid_argument
/// naming the pattern); so are patterns that match no channel: std::invalid_argument naming
/// each and the closest names, case ignored ("... matches no channel (names are case-sensitive);
/// the closest are: slider.x, slider.vx, slider.ax"); `time` alone is accepted and selects
/// nothing.
std::vector<std::size_t> select_channels(const std::vector<ChannelInfo>& channels,
                                         const std::vector<std::string>& patterns);

}  // namespace lash
