# The project's two commands: `make run` (set up, then the main job) and `make test` (set up, then every test).
.PHONY: setup run test

setup:
	bash scripts/setup.sh

run: setup
	python3 -m mantaray.cli sim run --video; test $$? -le 1  # 1 = target not reached: a result, not an error

test: setup
	python3 -m pytest
