# RoboDog: the two commands are `make demo` and `make test` (see README.md).
SHELL := /bin/bash
.DEFAULT_GOAL := help

.PHONY: help setup build test lint bench demo soak clean

help:
	@echo "make setup  - Debian packages + .venv (idempotent)"
	@echo "make build  - catkin_make into build/ and devel/ (then: source ./env.sh)"
	@echo "make test   - lint + every gtest, rostest and pytest; ends with 'N passed, M failed'"
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

lint: setup
	@tools/lint.sh

bench: build
	@tools/run_bench.sh

demo: build
	@tools/demo.sh

soak: build
	@tools/soak.sh

clean:
	rm -rf build devel install log test-results
