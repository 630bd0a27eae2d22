# splitray: `make render` renders the default scene, `make test` runs every test with the
# Vulkan validation layer on. Both install what is missing first (Debian 12, as root).

CARGO ?= cargo
SCENE ?= cornell-box
# Bidirectional path tracing with a light vertex cache, resampled connections and
# material sorting where it pays (README: the integrators), for a fixed time.
RENDER_FLAGS ?= --integrator cis-lbdpt --width 256 --height 256 --time 20

.PHONY: deps build render test slurm-test lint doc gpu-bundle bench clean

deps:
	@command -v $(CARGO) >/dev/null || { echo "make: cargo not found: install a Rust toolchain (rustup) first" >&2; exit 1; }
	@bash tools/install-deps.sh

build: deps
	$(CARGO) build --release --locked

render: build
	@mkdir -p out
	./target/release/splitray render $(SCENE) $(RENDER_FLAGS) -o out/$(SCENE).exr --stats out/$(SCENE).stats.json

# Every GPU test opens its device with VK_LAYER_KHRONOS_validation and fails on any
# validation error or warning (tests/suite/common/mod.rs); SPLITRAY_VALIDATION turns it on for
# anything else that opens a device. The `ci` profile (Cargo.toml) is release optimisation
# with debug assertions: the light-transport tests sample millions of paths.
#
# Where cargo-nextest is installed it runs the tests, each in a process of its own, two
# at a time: most tests keep one of two cores busy (`animation`: 41.5 s of CPU in 41.7
# s). Without it, `cargo test` runs the same tests in one process, where the GPU tests
# take turns on the device (tests/suite/common/turn.rs), so it takes longer.
test: deps
	@export SPLITRAY_VALIDATION=1; set -x; \
	if $(CARGO) nextest --version >/dev/null 2>&1; then \
	  $(CARGO) nextest run --cargo-profile ci --locked --all-targets --no-fail-fast; \
	else \
	  $(CARGO) test --profile ci --locked --all-targets; \
	fi

# A real one-node Slurm cluster on localhost (munged, slurmctld, slurmd) renders one
# image as a 4-task job array with a dependent merge job, checked against a one-process
# render (tools/slurm/test-local-cluster.sh: installs slurm-wlm and munge, runs as root,
# stops the daemons it started).
# The binary is built as `make test` builds it (with the test targets' features), so
# after `make test` this builds nothing.
slurm-test: deps
	$(CARGO) test --profile ci --locked --no-run --test suite
	bash tools/slurm/test-local-cluster.sh target/ci/splitray

# Clippy in the `ci` profile reuses what `make test` built (the build script's compiled
# shaders, the proc macros): 44 s after `make test` against 3.5 min in the dev profile.
lint:
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --profile ci --locked --all-targets -- -D warnings

# What checking splitray on a GPU machine without a Rust toolchain or a Vulkan loader
# needs (binaries, loader, validation layer), in .gpu-bundle/: tools/gpu-check.sh runs it
# there in a copy of this checkout.
gpu-bundle: deps
	bash tools/gpu-bundle.sh

# The API documentation in target/doc, with broken or private intra-doc links as errors.
# In the `ci` profile it reuses what `make test` built (about 25 s on 2 cores then).
doc:
	RUSTDOCFLAGS="-D warnings" $(CARGO) doc --profile ci --locked --no-deps

clean:
	$(CARGO) clean
	rm -rf out
