/// @file fuzz_model_loader.cpp
/// libFuzzer target: arbitrary bytes → lash::load_model_text → Workspace → initial_state.
///
/// The contract under test (io/model_loader.hpp, core/dynamics.hpp):
///   - load_model_text throws lash::ModelError for every bad input, and nothing else;
///   - a model it accepts is in the ranges core/model.hpp documents (fuzz_contract.hpp), builds
///     a Workspace (which compiles every expression) without throwing,
///     and initial_state either assembles it or throws std::runtime_error;
///   - a model of at most kMaxRunBodies bodies that assembles runs for a bounded effort
///     (fuzz_contract.hpp run_contract_violation: at most 2000 steps and 20 outputs) and ends
///     with a status that says what happened.
/// Any other exception, a crash, a sanitizer report or a hang is a bug; the target aborts on it
/// so libFuzzer saves the input.
///
/// Leading lines of the form `#set KEY.PATH=VALUE` (YAML comments, so the text stays a valid
/// model) are also passed as overrides, as `lash run --set` would, to exercise apply_override.
///
/// Run: scripts/fuzz-smoke.sh, or by hand
///   build-fuzz/fuzz/fuzz_model_loader -dict=fuzz/yaml.dict -max_len=4096 CORPUS_DIR
/// or on given files (LASH_FUZZ_VERBOSE=1 prints how far each one got)
///   LASH_FUZZ_VERBOSE=1 build-fuzz/fuzz/fuzz_model_loader fuzz/corpus/*
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <optional>
#include <string>
#include <typeinfo>
#include <vector>

#include "core/dynamics.hpp"
#include "fuzz_contract.hpp"
#include "io/model_loader.hpp"

namespace {

// Inputs above this size only slow the search; models in examples/ are ~3 kB.
constexpr size_t kMaxInputBytes = 64 * 1024;
// Assembly is a dense Gauss–Newton on 3·bodies unknowns, up to 100 iterations: legitimate but
// slow work for big models, which would show up as fuzzer timeouts rather than bugs.
constexpr size_t kMaxAssembledBodies = 64;
// Runs are bounded in steps, but a step of a big model is slow: run the small ones.
constexpr size_t kMaxRunBodies = 12;

const bool kVerbose = std::getenv("LASH_FUZZ_VERBOSE") != nullptr;

[[noreturn]] void fail(const char* stage, const std::exception* e) {
  std::fprintf(stderr, "\n*** fuzz_model_loader: unexpected exception in %s: %s: %s\n", stage,
               e ? typeid(*e).name() : "(not a std::exception)", e ? e->what() : "");
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > kMaxInputBytes) return -1;  // not added to the corpus
  const std::string text(reinterpret_cast<const char*>(data), size);

  // Stage 1: load. ModelError is the expected answer to bad input.
  std::optional<lash::LoadedModel> loaded;
  try {
    loaded = lash::load_model_text(text, "fuzz.yaml", lash::fuzz::overrides_of(text));
  } catch (const lash::ModelError& e) {
    if (kVerbose) std::fprintf(stderr, "rejected: %s", e.what());
    return 0;
  } catch (const std::exception& e) {
    fail("load_model_text", &e);
  } catch (...) {
    fail("load_model_text", nullptr);
  }

  // Stage 2: what the loader accepted is a validated model.
  const lash::Model& model = loaded->model;
  const std::string violation = lash::fuzz::model_invariant_violation(model);
  if (!violation.empty()) {
    std::fprintf(stderr, "\n*** fuzz_model_loader: accepted an invalid model: %s\n",
                 violation.c_str());
    std::abort();
  }

  // Stage 3: compile expressions and assemble. runtime_error = "cannot assemble", expected.
  if (model.bodies.size() > kMaxAssembledBodies) return 0;
  if (kVerbose) std::fprintf(stderr, "loaded: %zu bodies\n", model.bodies.size());
  bool assembled = false;
  try {
    lash::Workspace ws(model);
    try {
      lash::initial_state(model, ws);
      assembled = true;
      if (kVerbose) std::fprintf(stderr, "assembled\n");
    } catch (const std::runtime_error& e) {
      if (kVerbose) std::fprintf(stderr, "not assembled: %s\n", e.what());
    }
  } catch (const std::exception& e) {
    fail("Workspace / initial_state", &e);
  } catch (...) {
    fail("Workspace / initial_state", nullptr);
  }

  // Stage 4: run it, bounded.
  if (!assembled || model.bodies.size() > kMaxRunBodies) return 0;
  std::string violation_run;
  try {
    violation_run = lash::fuzz::run_contract_violation(model);
  } catch (...) {
    fail("simulate", nullptr);
  }
  if (!violation_run.empty()) {
    std::fprintf(stderr, "\n*** fuzz_model_loader: run broke its contract: %s\n", violation_run.c_str());
    std::abort();
  }
  if (kVerbose) std::fprintf(stderr, "ran\n");
  return 0;
}
