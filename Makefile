# ForaNav: two commands do all set-up — `make demo` (the main job) and `make test`.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: setup test demo bench paper-tests deploy clean camera-runtime docs capp capp-asan bolt firmware-sil crtp-screenshot

setup: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	$(MAKE) capp
	$(BIN)/python -m crazyflie_app.firmware.sil.build --if-available
	touch $(STAMP)

# The C flight app (crazyflie_app/bolt, docs/bolt.md). capp: the pure core as a host shared library, loaded by
# crazyflie_app/bolt/c_core.py (foranav fly --app c); capp-asan: the same under AddressSanitizer + UBSan, with the
# differential test and a flight run against it; bolt: the Bolt firmware with the app, from a firmware checkout.
CAPP_DIR     := crazyflie_app/bolt
# the core's files are nav_* (with the host-only nav_host.c), as in crazyflie_app/bolt/c_core.py
CAPP_SOURCES := $(sort $(wildcard $(CAPP_DIR)/src/nav_*.c))
CAPP_HEADERS := $(sort $(wildcard $(CAPP_DIR)/src/nav_*.h))
CAPP_CFLAGS  := -std=c11 -O2 -Wall -Wextra -Werror -fPIC -shared
ASAN_FLAGS   := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all

capp: build/libforanav_nav.so

build/libforanav_nav.so: $(CAPP_SOURCES) $(CAPP_HEADERS)
	mkdir -p build
	gcc $(CAPP_CFLAGS) -o $@ $(CAPP_SOURCES) -lm

build/libforanav_nav_asan.so: $(CAPP_SOURCES) $(CAPP_HEADERS)
	mkdir -p build
	gcc $(CAPP_CFLAGS) -g $(ASAN_FLAGS) -o $@ $(CAPP_SOURCES) -lm

# the default-suite differential test, the C app's flights and the UART2 tests; CAPP_ASAN_MARK="slow or not slow"
# adds the 20 random plantations and the paper maps 2-3
CAPP_ASAN_MARK ?= not slow
capp-asan: build/libforanav_nav_asan.so
	FORANAV_CAPP_LIB=$(CURDIR)/build/libforanav_nav_asan.so \
	LD_PRELOAD="$$(gcc -print-file-name=libasan.so) $$(gcc -print-file-name=libubsan.so)" \
	ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 PYTHONMALLOC=malloc \
	$(BIN)/python -m pytest -q -p no:cacheprovider -m "$(CAPP_ASAN_MARK)" \
		tests/crazyflie_app/bolt/test_differential_c_vs_python.py tests/crazyflie_app/bolt/test_c_app.py \
		tests/crazyflie_app/firmware/test_uart2.py

bolt:
	@test -n "$(CRAZYFLIE_BASE)" || { echo "usage: make bolt CRAZYFLIE_BASE=/path/to/crazyflie-firmware"; exit 2; }
	mkdir -p $(CAPP_DIR)/build
	@# not a git checkout (a snapshot): the firmware's version script needs a build_info.json
	test -d "$(CRAZYFLIE_BASE)/.git" || test -f $(CAPP_DIR)/build/build_info.json || \
		echo '{"tag": "snapshot"}' > $(CAPP_DIR)/build/build_info.json
	$(MAKE) -C $(CAPP_DIR) CRAZYFLIE_BASE=$(abspath $(CRAZYFLIE_BASE)) bolt_defconfig
	$(MAKE) -C $(CAPP_DIR) CRAZYFLIE_BASE=$(abspath $(CRAZYFLIE_BASE)) -j2
	@ls -l $(CAPP_DIR)/build/bolt.bin

# The firmware plant (foranav fly --plant firmware): the real Crazyflie firmware's commander, supervisor, PID
# controller and Kalman estimator, built for the host with a rigid-body plant, and the firmware's cffirmware
# bindings (crazyflie_app/firmware/sil/build.py). From ../shared/vendor/crazyflie-firmware-*.tar.gz or
# FORANAV_FIRMWARE=PATH (a tarball or a checkout); make setup builds it when the firmware is there.
firmware-sil: $(STAMP)
	$(BIN)/python -m crazyflie_app.firmware.sil.build

test: $(STAMP) capp camera-runtime
	$(BIN)/python -m crazyflie_app.firmware.sil.build --if-available
	$(BIN)/python -m pytest -q

# The camera's own runtime (Python 3.7 + numpy 1.16.6 + OpenCV 4.10) in .venv-camera/, built once from the
# machine's Python 3.7 (a stamp file inside makes a second run a no-op); tests/cross_cutting/test_camera_runtime.py
# uses it.
camera-runtime: $(STAMP)
	$(BIN)/python -m host_tools.jevois_host.camera_runtime build

# docs/reference/*.md from the code (commands, flight app PARAMs, camera module parameters)
docs: $(STAMP)
	$(BIN)/python -m host_tools.docs_gen
	$(BIN)/python -m tests.cross_cutting.test_cli_bad_inputs --write > /dev/null

demo: $(STAMP)
	$(BIN)/foranav demo

bench: $(STAMP)
	$(BIN)/foranav bench sim
	$(BIN)/foranav bench detector

paper-tests: $(STAMP)
	$(BIN)/foranav paper-tests --out runs/paper-tests

# docs/img/crtp_cfclient_plotter.png (docs/crtp.md): stock cfclient under Xvfb, connected to a --realtime flight.
# Needs apt packages xvfb x11-utils xdotool imagemagick libxcb-cursor0; cfclient goes in its own venv (it pins
# PyQt6 and numpy versions the project does not need).
CFCLIENT_VENV := build/cfclient-venv
CFCLIENT_VERSION := 2026.8.1
crtp-screenshot: $(STAMP)
	test -x $(CFCLIENT_VENV)/bin/cfclient || { $(PYTHON) -m venv $(CFCLIENT_VENV) && \
		$(CFCLIENT_VENV)/bin/python -m pip install --quiet cfclient==$(CFCLIENT_VERSION); }
	$(BIN)/python -m host_tools.flight.crtp_screenshot --cfclient $(CFCLIENT_VENV)/bin/cfclient \
		--out docs/img/crtp_cfclient_plotter.png

deploy: $(STAMP)
	@test -n "$(SD)" || { echo "usage: make deploy SD=/path/to/JEVOIS [DEPLOY_FLAGS=--headless]"; exit 2; }
	$(BIN)/foranav deploy --sd "$(SD)" $(DEPLOY_FLAGS)

clean:
	rm -rf $(VENV) .venv-camera runs .pytest_cache build $(CAPP_DIR)/build
