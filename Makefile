# The project's two commands: `make run` (set up, then the main job) and `make test` (set up, then every test);
# `make lint` (the style gates, first in CI) and `make test-fast` (the tests not marked slow, for development).
.PHONY: setup run test test-fast lint

FIRMWARE_SOURCES = $(shell git ls-files 'firmware/*.c' 'firmware/*.cpp' 'firmware/*.h' 'sim/model/plugin/*.c' | grep -v '_gen\.h$$')

setup:
	bash scripts/setup.sh

run: setup
	python3 -m mantaray.cli sim run --video; test $$? -le 1  # 1 = target not reached: a result, not an error

test: setup
	python3 -m pytest

test-fast: setup
	python3 -m pytest -m "not slow"

lint: setup
	python3 -m ruff check .
	python3 -m ruff format --check .
	python3 -m mypy
	clang-format --dry-run --Werror $(FIRMWARE_SOURCES)
