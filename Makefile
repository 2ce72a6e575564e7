.PHONY: install lint type test test-all perf
install:
	pip install -c constraints.txt -e ".[dev]"
lint:
	ruff check . && ruff format --check usvsim guidance learning baselines
type:
	mypy
test:
	python -m pytest
perf:
	usvsim perf
