# hairdyn: `make demo` runs the main job, `make test` runs every test. Both set up the
# machine first (Debian packages, the bpy venv) and build the native module.
CMAKE := /usr/bin/cmake
BUILD := build
JOBS ?= 2

.PHONY: setup build test demo demo-lcp bench package fixtures clean

setup:
	@scripts/setup.sh

build: setup
	@$(CMAKE) -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DPython_EXECUTABLE=/usr/bin/python3.11 >/dev/null
	@$(CMAKE) --build $(BUILD) -j$(JOBS)

test: build
	@scripts/test.sh

demo: build
	blender -b blend_fixtures/head_shake.blend --python-exit-code 1 --python scripts/demo.py -- $(CURDIR)/out/demo

demo-lcp: build
	blender -b blend_fixtures/head_shake.blend --python-exit-code 1 --python scripts/demo.py -- $(CURDIR)/out/demo_lcp LCP

bench: build
	$(BUILD)/hairdyn_bench --benchmark_counters_tabular=true
	blender -b blend_fixtures/head_particles.blend --python-exit-code 1 \
	  --python scripts/bench_blender_hair.py -- out/bench/blender_hair.json
	blender -b --factory-startup --python-exit-code 1 \
	  --python scripts/bench_playback.py -- out/bench/playback.json
	blender -b --factory-startup --python-exit-code 1 \
	  --python scripts/bench_lcp_groom.py -- out/bench/lcp_groom.json

package: build
	python3 scripts/package.py out/dist

fixtures:
	blender -b --factory-startup --python-exit-code 1 --python blend_fixtures/make_fixtures.py
	rm -f blend_fixtures/*.blend1

clean:
	rm -rf $(BUILD) out addon/hairdyn/_native*.so
