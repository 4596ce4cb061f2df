# Two entry points for a fresh machine: `make test` and `make demo`.
# Everything installs into .venv from requirements.txt (exact pins).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin

.PHONY: test demo venv clean

# Keep DDS traffic on this machine, over UDP (no stale shared-memory files).
ROS_ENV := ROS_DOMAIN_ID=$${ROS_DOMAIN_ID:-42} ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST \
	FASTDDS_BUILTIN_TRANSPORTS=UDPv4

$(VENV)/.installed: requirements.txt setup.py denoise_imu_ros/pipeline/_step.c denoise_imu_ros/learn/_block.c
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip==25.3
	$(BIN)/pip install --quiet -r requirements.txt
	$(BIN)/pip install --quiet --no-deps -e .
	touch $@

venv: $(VENV)/.installed

# Unit, integration and lint tests (tests needing ../shared/data skip without it), on
# two processes (each its own DDS domain); prints the wall time of the tests alone.
# Torch's OpenMP threads sleep when idle instead of spinning: two pytest processes share
# the cores, and one's spinning threads took CPU the other's work needed. Bytecode is
# written even where the environment turns it off (PYTHONDONTWRITEBYTECODE): each
# interpreter a test starts then reads the package compiled instead of compiling it.
test: venv
	@start=$$(date +%s); $(ROS_ENV) OMP_WAIT_POLICY=PASSIVE PYTHONDONTWRITEBYTECODE= $(BIN)/python -m pytest -n 2 --dist worksteal test; status=$$?; \
	echo "make test: tests took $$(( $$(date +%s) - start )) s"; exit $$status

# The bundled EuRoC test-sequence sample (90 s of V1_03): offline evaluation with the
# shipped model, then the live run: gyro_denoiser + bag player + monitor over DDS.
demo: venv
	$(BIN)/denoise-imu eval --model euroc --data denoise_imu_ros/sample \
		--sequences euroc_V1_03_90s --out demo_out
	$(ROS_ENV) $(BIN)/python -m denoise_imu_ros.demo --model euroc --out demo_out
	@echo "tables and figures in demo_out/"

clean:
	rm -rf $(VENV) demo_out build install log
