# Lash: `make demo` and `make test` work on a fresh Debian machine (they install what is missing).
BUILD      ?= build
JOBS       ?= $(shell nproc)
CMAKE_ARGS ?=

.PHONY: deps build python install demo test test-sanitize test-tsan fuzz bench studies clean

deps:
	@bash scripts/install-deps.sh

build: deps
	@cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release $(CMAKE_ARGS) >/dev/null
	@cmake --build $(BUILD) -j $(JOBS)

# The Python module alone: build/python/lash (PYTHONPATH=build/python /usr/bin/python3).
python: deps
	@cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release $(CMAKE_ARGS) >/dev/null
	@cmake --build $(BUILD) -j $(JOBS) --target lash_python

# Installs the lash command, the C++ package and the Python module under PREFIX (default
# /usr/local, whose lib/python3.X/dist-packages Debian's /usr/bin/python3 reads).
PREFIX ?= /usr/local
install: build
	cmake --install $(BUILD) --prefix $(PREFIX)

demo: build
	$(BUILD)/lash run examples/flores_slider_crank.yaml -o out/flores_slider_crank --report

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

# The whole suite once more under AddressSanitizer + UndefinedBehaviorSanitizer (tests/lsan.supp:
# leaks inside libraries, not Lash's: CLN's static initialiser, GiNaC's parser on a division by 0; the build needs it too, since listing the
# tests runs each test program). -O2 with line tables only (-g1: file and line in every report's
# stack, no variable info): about 20% less compile time than -O2 -g, which is most of this
# target's time. At -O0 and at -O1, GiNaC's parser (libginac 1.8.6) crashes inside the library
# (function::eval) for every driver expression under ASan, which -O2 and the plain builds do not
# (-O1 -g1 would have saved 40%). The library is built as a unity build (each component's sources
# compiled as one file, so Eigen's and the standard library's templates are instantiated once:
# lash_core 151 s → 116 s of wall time on 2 cores, measured), and the test programs at -O1
# (tests/CMakeLists.txt; they call GiNaC only through the library): with both, the whole
# sanitizer build took 9 min on 2 cores (2026-11-28, with other compiles beside it), where the
# last CI run's took about 25.
SANITIZE_FLAGS = -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" \
  -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" -DLASH_BENCH=OFF -DCMAKE_UNITY_BUILD=ON
test-sanitize: deps
	@cmake -S . -B build-sanitize -G Ninja $(SANITIZE_FLAGS) -DLASH_SANITIZE=ON >/dev/null
	@LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0 cmake --build build-sanitize -j $(JOBS)
	cd build-sanitize && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0 ctest --output-on-failure -j $(JOBS)

# The code that runs on several threads (concurrent simulations, FFTW planning) under
# ThreadSanitizer: only test_threads and test_signal are built and run, in build-tsan/.
# halt_on_error: the first report fails the target; tests/tsan.supp lists accepted reports.
test-tsan: deps
	@cmake -S . -B build-tsan -G Ninja $(SANITIZE_FLAGS) -DLASH_TSAN=ON >/dev/null
	@cmake --build build-tsan -j $(JOBS) --target test_threads test_signal
	for t in test_threads test_signal; do \
	  TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1 suppressions=$(CURDIR)/tests/tsan.supp" \
	    build-tsan/tests/$$t || exit 1; \
	done

bench: build
	$(BUILD)/bench/bench_flores

# The studies of studies/ (minutes each on two cores) into out/, with their reports and their
# RESULTS.md (studies/results.py), which is also copied to studies/NAME/RESULTS.md.
studies: build
	for s in studies/*.yaml; do \
	  n=$$(basename $$s .yaml); \
	  $(BUILD)/lash sweep $$s -o out/$$n --resume -j $(JOBS) && $(BUILD)/lash report out/$$n && \
	    python3 studies/results.py out/$$n --copy-to studies/$$n || exit 1; \
	done
	for d in out/breaker_*/; do python3 studies/breaker_metrics.py $$d --csv $$d/breaker_metrics.csv || exit 1; done

clean:
	rm -rf $(BUILD) build-sanitize build-tsan build-fuzz out

# libFuzzer on the model loader (clang, ASan/UBSan) in build-fuzz/; LASH_FUZZ_SECONDS=300 for longer.
fuzz: deps
	LASH_FUZZ_JOBS=$(JOBS) bash scripts/fuzz-smoke.sh
