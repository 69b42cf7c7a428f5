# objmap — set-up, build, test, demo and benchmarks. `make demo` and `make test` do all set-up.
BUILD ?= build
JOBS ?= 2
DATA ?= $(if $(OBJMAP_DATA),$(OBJMAP_DATA),$(abspath ../shared/data))
DEMO ?= out/demo
OBJMAP := $(BUILD)/bin/objmap

FUZZ_SECONDS ?= 60

.PHONY: all deps configure build test test-slurm demo bench bench-detect bench-follow bench-memory ablation fuzz sanitize format clean

all: build

deps:
	@bash scripts/install-deps.sh

$(BUILD)/CMakeCache.txt:
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DOBJMAP_BUILD_TESTS=ON -DOBJMAP_BUILD_BENCHMARKS=ON

configure: $(BUILD)/CMakeCache.txt

# build: everything, the benchmark programs too; test: what ctest runs (`all`: not the benchmarks).
build: deps configure
	cmake --build $(BUILD) -j$(JOBS) --target all benchmarks

test: deps configure
	cmake --build $(BUILD) -j$(JOBS)
	cd $(BUILD) && OBJMAP_DATA=$(DATA) ctest --output-on-failure -j$(JOBS)

# make test-slurm: the workflow (scripts/workflow/Snakefile) on three synthetic recordings through a real
# single-node Slurm that the script starts as root in a temporary folder and stops at the end
# (scripts/test_slurm.sh, about 2 minutes; not part of make test). docs/workflow.md.
test-slurm: configure
	@bash scripts/install-deps.sh --slurm
	cmake --build $(BUILD) -j$(JOBS) --target objmap_app
	@bash scripts/test_slurm.sh $(OBJMAP)

# The demo needs only the objmap binary: it is built first, without the tests and benchmarks.
demo: deps configure
	cmake --build $(BUILD) -j$(JOBS) --target objmap_app
	@bash scripts/demo.sh $(OBJMAP) $(DEMO)

# make bench [DATA=DIR]: every table of docs/benchmarks.md on the sequences under DATA plus three
# synthetic scenes (scripts/bench.sh; about 10 minutes on 2 cores), then the ablation (below,
# about 20 minutes more; BENCH_ABLATION=0 leaves it out); writes the generated sections of
# docs/benchmarks.md and docs/fusion.md and out/bench/; then bench-detect and bench-follow (below;
# BENCH_DETECT=0, BENCH_FOLLOW=0 leave them out). Installs python3-open3d for the Open3D baseline if
# it can.
bench: deps build
	@bash scripts/install-deps.sh --bench
	@BENCH_COMMAND="make bench$(if $(filter command line,$(origin DATA)), DATA=$(DATA))" \
	  bash scripts/bench.sh $(OBJMAP) $(DATA)
	@[ "$(BENCH_DETECT)" = 0 ] || bash scripts/bench_detect.sh $(OBJMAP) $(DATA) out/bench/detect
	@[ "$(BENCH_FOLLOW)" = 0 ] || bash scripts/bench_follow.sh $(OBJMAP) $(DATA) out/bench/follow

# make bench-detect [DATA=DIR]: objmap detect's frames/s per backend (OpenCV's dnn, ONNX Runtime)
# and thread count on the first 40 frames of fr1_rpy_every4, interleaved rounds, medians, and the
# masks of each against the reference (scripts/bench_detect.sh; about 5 minutes on 2 cores; also
# the end of make bench, BENCH_DETECT=0 leaves it out). docs/benchmarks.md, "Speed of detect".
bench-detect: deps build
	@bash scripts/bench_detect.sh $(OBJMAP) $(DATA) out/bench_detect

# make bench-follow [DATA=DIR]: objmap follow while objmap replay writes a recording at 1x speed:
# fr1_rpy_every4 and the 7-Scenes clip (detect with YOLOv5n-seg; against objmap run with the same
# model), the synthetic walk-through and one table circled at 300 and 1200 frames (against objmap
# fuse): lag median and max, keyframes skipped by detect, objects, peak memory and its ratio 1200 vs
# 300 frames (scripts/bench_follow.sh; about 13 minutes on 2 cores the first time, the scenes are kept in
# out/bench_follow/; also the end of make bench, BENCH_FOLLOW=0 leaves it out).
# docs/benchmarks.md, "Following a recording".
bench-follow: build
	@bash scripts/bench_follow.sh $(OBJMAP) $(DATA) out/bench_follow

# make bench-memory: peak memory and dense-map voxels of objmap fuse on a synthetic scene circled
# for 300 and 1200 frames, with and without the dense map's pruning, then the peak memory of objmap
# track on the synthetic walk-through at 300 and 954 frames (scripts/bench_memory.sh; about 8
# minutes on 2 cores the first time, the scenes are kept in out/bench_memory/).
bench-memory: build
	@bash scripts/bench_memory.sh $(OBJMAP) out/bench_memory

# make ablation [DATA=DIR]: only the ablation part of make bench (scripts/ablation.sh): paper vs
# objmap vs objmap with each change reverted on every sequence, and the eq 22 weight sweep;
# writes their generated sections of docs/benchmarks.md and docs/fusion.md and out/ablation/.
ablation: deps configure
	cmake --build $(BUILD) -j$(JOBS) --target objmap_app
	@ABLATION_COMMAND="make ablation$(if $(filter command line,$(origin DATA)), DATA=$(DATA))" \
	  bash scripts/ablation.sh $(OBJMAP) $(DATA)

# make fuzz [FUZZ_SECONDS=60] [FUZZ_TARGETS="png ply"]: each fuzz target of tests/fuzz/ (every reader of
# outside data) for FUZZ_SECONDS under libFuzzer + ASan + UBSan, built with clang in build-fuzz/
# (scripts/fuzz.sh; 25 targets: ~26 minutes at the default). docs/testing.md.
fuzz:
	@bash scripts/install-deps.sh --fuzz
	@FUZZ_SECONDS=$(FUZZ_SECONDS) JOBS=$(JOBS) bash scripts/fuzz.sh $(DATA)

# make sanitize: the whole test suite on an ASan + UBSan build in build-asan/ (scripts/sanitize.sh;
# the first build takes long: docs/testing.md gives the figures).
sanitize: deps
	@JOBS=$(JOBS) bash scripts/sanitize.sh $(DATA)

format:
	@bash scripts/format.sh

clean:
	rm -rf $(BUILD) build-fuzz build-asan out
