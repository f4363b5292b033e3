// Replays every input in tests/fuzz_regressions/ (crashes found by fuzz/fuzz_model_loader, plus
// hand-made hostile inputs) through the loader, with the fuzzer's contract:
//   - load_model_text throws lash::ModelError, with at least one diagnostic, and nothing else;
//   - a model it accepts is in the ranges core/model.hpp documents (fuzz/fuzz_contract.hpp),
//     builds a Workspace without throwing, and initial_state assembles it or throws
//     std::runtime_error; one that assembles runs for a bounded effort and ends with a status
//     that says what happened.
// Without sanitizers this catches the exceptions and hard crashes; scripts/fuzz-smoke.sh replays
// the same files under ASan/UBSan. Each file is one test case, named after the file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <typeinfo>
#include <vector>

#include "../fuzz/fuzz_contract.hpp"  // the contract the fuzzer checks
#include "core/dynamics.hpp"
#include "io/model_loader.hpp"

namespace fs = std::filesystem;

namespace {

const fs::path kDir = fs::path(LASH_SOURCE_DIR) / "tests" / "fuzz_regressions";

std::vector<std::string> regression_files() {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(kDir, ec))
    if (entry.is_regular_file() && entry.path().filename().string() != "README.md")
      names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

class FuzzRegression : public ::testing::TestWithParam<std::string> {};

TEST_P(FuzzRegression, OnlyModelErrorEscapes) {
  const std::string text = read_bytes(kDir / GetParam());
  lash::LoadedModel loaded;
  try {
    loaded = lash::load_model_text(text, GetParam(), lash::fuzz::overrides_of(text));
  } catch (const lash::ModelError& e) {
    EXPECT_FALSE(e.diagnostics().empty()) << "a ModelError must carry at least one diagnostic";
    return;
  } catch (const std::exception& e) {
    FAIL() << "load_model_text threw " << typeid(e).name() << ": " << e.what();
  } catch (...) {
    FAIL() << "load_model_text threw a non-std exception";
  }

  // Accepted: the model must be valid, compile, and either assemble or say why not.
  EXPECT_EQ(lash::fuzz::model_invariant_violation(loaded.model), "");
  bool assembled = false;
  try {
    lash::Workspace ws(loaded.model);
    try {
      lash::initial_state(loaded.model, ws);
      assembled = true;
    } catch (const std::runtime_error&) {
    }
  } catch (const std::exception& e) {
    FAIL() << "an accepted model failed in Workspace/initial_state with " << typeid(e).name()
           << ": " << e.what();
  }
  // Assembled: a bounded run ends with a status that says what happened.
  if (assembled) {
    EXPECT_EQ(lash::fuzz::run_contract_violation(loaded.model), "");
  }
}

TEST(FuzzRegressions, FolderHasInputs) {
  EXPECT_FALSE(regression_files().empty()) << "no inputs in " << kDir;
}

std::string test_name(const ::testing::TestParamInfo<std::string>& info) {
  std::string name = info.param;
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return name;
}

INSTANTIATE_TEST_SUITE_P(Inputs, FuzzRegression, ::testing::ValuesIn(regression_files()),
                         test_name);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(FuzzRegression);

}  // namespace
