# The two commands of the README: `make render` and `make test`.
# Both install the Debian dependencies (scripts/install-deps.sh) and configure; `make render`
# builds only the renderer and the Python module (`import bounce` then works for the system
# Python and Blender), `make test` everything (the test suite, benchmarks).
BUILD ?= build
JOBS ?= $(shell nproc)
SCENE ?= scenes/cornell/cornell.json
OUT ?= out/cornell.exr

.PHONY: deps configure build renderer render test clean

deps:
	./scripts/install-deps.sh
	npm ci --no-audit --no-fund --loglevel=error

configure: deps
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release

build: configure
	cmake --build $(BUILD) -j $(JOBS)
	./scripts/install-python.sh $(BUILD)

renderer: configure
	cmake --build $(BUILD) -j $(JOBS) --target bounce bounce_python
	./scripts/install-python.sh $(BUILD)

render: renderer
	mkdir -p $(dir $(OUT))
	$(BUILD)/bounce render $(SCENE) -o $(OUT) --gi cache --rays 1024 --stats

test: build
	ctest --test-dir $(BUILD) --output-on-failure -j $(JOBS)

clean:
	rm -rf $(BUILD) out
