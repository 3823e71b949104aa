# The project's two commands: `make run` (set up, then the main job) and `make test` (set up, then every test).
.PHONY: setup run test

setup:
	bash scripts/setup.sh

run: setup
	python3 -m mantaray.cli vmcu --identify-only

test: setup
	python3 -m pytest
