# Two entry points for a fresh machine: `make test` and `make demo`.
# Everything installs into .venv from requirements.txt (exact pins).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
DATA ?= ../shared/data

.PHONY: test demo venv clean

$(VENV)/.installed: requirements.txt setup.py
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip==25.3
	$(BIN)/pip install --quiet -r requirements.txt
	$(BIN)/pip install --quiet --no-deps -e .
	touch $@

venv: $(VENV)/.installed

# Unit, integration and lint tests (tests needing ../shared/data skip without it).
test: venv
	FASTDDS_BUILTIN_TRANSPORTS=UDPv4 ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST \
		$(BIN)/python -m pytest test

# Offline correction + evaluation of the shipped EuRoC sample with the shipped model.
demo: venv
	$(BIN)/denoise-imu eval --model euroc --data denoise_imu_ros/sample \
		--sequences euroc_V1_03_90s --out demo_out
	@echo "figures and tables in demo_out/"

clean:
	rm -rf $(VENV) demo_out build install log
