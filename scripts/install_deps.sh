#!/usr/bin/env bash
# Installs everything rotorid needs to build, test and plot on a fresh Debian 12 machine (run as root).
# gfortran brings libgfortran.a, which the static link of LAPACK needs (cmake/RotoridStaticDependencies.cmake).
# libsdformat-dev is optional: export_sdformat_test loads the exported gz models with it (skips without).
set -euo pipefail
export DEBIAN_FRONTEND=noninteractive
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends \
  build-essential cmake ninja-build pkg-config python3 \
  libeigen3-dev libceres-dev libgoogle-glog-dev libgflags-dev \
  libgtest-dev libgmock-dev libbenchmark-dev \
  libcli11-dev nlohmann-json3-dev libyaml-cpp-dev libfast-float-dev \
  gfortran \
  libsdformat-dev \
  gnuplot-nox
