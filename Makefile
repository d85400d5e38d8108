# RoboDog: the two commands are `make demo` and `make test` (see README.md).
SHELL := /bin/bash
.DEFAULT_GOAL := help

.PHONY: help setup build test test-long lint bench demo soak clean

help:
	@echo "make setup  - Debian packages + .venv (idempotent)"
	@echo "make build  - catkin_make into build/ and devel/ (then: source ./env.sh)"
	@echo "make test   - lint + every gtest, rostest and pytest; ends with 'N passed, M failed'"
	@echo "make test-long - the tests marked long (colcon/catkin build drop-in); CI runs it after make test"
	@echo "make bench  - benchmarks (numbers with ratios from one run)"
	@echo "make lint   - catkin_lint, ruff, vermin, clang-format"
	@echo "make demo   - the whole system in simulation with a scripted audience (VISUAL=1 for RViz + GUI)"
	@echo "make soak   - the long crowd soak"

setup:
	@tools/setup.sh

build: setup
	@tools/build.sh

test: build
	@tools/run_tests.sh

test-long: build
	@tools/run_long_tests.sh

lint: setup
	@tools/lint.sh

bench: build
	@tools/run_bench.sh

demo: build
	@tools/demo.sh

soak: build
	@tools/soak.sh

clean:
	rm -rf build devel install log test-results test-results-long
