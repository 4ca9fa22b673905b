# The Debian package: CPack's DEB generator over what `cmake --install` installs (the CLI, libvdb_ewa.so
# and its image module, the headers, the CMake package, the Python module and its stub), under /usr,
# as vdb_ewa_VERSION_ARCH.deb (package vdb-ewa: Debian's names take no underscore).
# scripts/package.sh builds it (a tree configured for the prefix /usr: the library in
# /usr/lib/<multiarch>, the module in /usr/lib/python3/dist-packages); ctest package.deb packages the
# test tree and runs what it extracts. docs/install.md.
set(VDB_EWA_PACKAGE_MAINTAINER "vdb_ewa maintainers <maintainers@users.noreply.h-seed-8eeaf125.example>" CACHE STRING
  "The .deb's Maintainer field, \"Name <email>\" (scripts/package.sh --maintainer)")
set(VDB_EWA_PACKAGE_HOMEPAGE "" CACHE STRING "The .deb's Homepage field (empty: none; scripts/package.sh --homepage)")

# The architecture dpkg names (amd64), in the file name as in the package.
execute_process(COMMAND dpkg --print-architecture OUTPUT_VARIABLE _vdb_ewa_deb_arch
  OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE _vdb_ewa_dpkg_result)
if(NOT _vdb_ewa_dpkg_result EQUAL 0 OR NOT _vdb_ewa_deb_arch)
  if(CMAKE_SYSTEM_PROCESSOR MATCHES "^(x86_64|AMD64)$")
    set(_vdb_ewa_deb_arch amd64)
  elseif(CMAKE_SYSTEM_PROCESSOR MATCHES "^(aarch64|arm64)$")
    set(_vdb_ewa_deb_arch arm64)
  else()
    set(_vdb_ewa_deb_arch "${CMAKE_SYSTEM_PROCESSOR}")
  endif()
endif()

# /usr/share/doc/vdb-ewa/copyright, Debian's place for the licence (machine-readable format).
set(_vdb_ewa_copyright "${PROJECT_BINARY_DIR}/copyright")
file(CONFIGURE OUTPUT "${_vdb_ewa_copyright}" CONTENT [[
Format: https://www.debian.org/doc/packaging-manuals/copyright-format/1.0/
Upstream-Name: vdb_ewa
Upstream-Contact: @VDB_EWA_PACKAGE_MAINTAINER@

Files: *
Copyright: the vdb_ewa authors
License: Apache-2.0
 Licensed under the Apache License, Version 2.0 (the "License"); you may not use
 this software except in compliance with the License. Unless required by
 applicable law or agreed to in writing, software distributed under the License
 is distributed on an "AS IS" BASIS, WITHOUT WARRANTIES OR CONDITIONS OF ANY
 KIND, either express or implied.
 .
 On Debian systems, the full text of the Apache License, Version 2.0 can be
 found in /usr/share/common-licenses/Apache-2.0.
]] @ONLY)
install(FILES "${_vdb_ewa_copyright}" DESTINATION "${CMAKE_INSTALL_DATAROOTDIR}/doc/vdb-ewa")

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME vdb_ewa)
set(CPACK_PACKAGE_VENDOR "vdb_ewa")
set(CPACK_PACKAGE_VERSION "${PROJECT_VERSION}")
set(CPACK_PACKAGE_CONTACT "${VDB_EWA_PACKAGE_MAINTAINER}")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "EWA volume-splatting renderer for OpenVDB fog volumes")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_PACKAGE_NAME vdb-ewa)
set(CPACK_DEBIAN_FILE_NAME "vdb_ewa_${PROJECT_VERSION}_${_vdb_ewa_deb_arch}.deb")
set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE "${_vdb_ewa_deb_arch}")
set(CPACK_DEBIAN_PACKAGE_MAINTAINER "${VDB_EWA_PACKAGE_MAINTAINER}")
set(CPACK_DEBIAN_PACKAGE_SECTION graphics)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
if(VDB_EWA_PACKAGE_HOMEPAGE)
  set(CPACK_DEBIAN_PACKAGE_HOMEPAGE "${VDB_EWA_PACKAGE_HOMEPAGE}")
endif()
# The extended description (CPack puts the summary above it), at most 80 columns a line.
string(CONCAT CPACK_DEBIAN_PACKAGE_DESCRIPTION
  "vdb_ewa renders OpenVDB grids by EWA volume splatting (Zwicker et al. 2002):\n"
  "every active voxel becomes a Gaussian kernel, projected, low-pass filtered\n"
  "and composited front to back. Its command line mirrors OpenVDB's vdb_render;\n"
  "it writes OpenEXR (beauty, depth, AOVs, deep) through OpenColorIO, and\n"
  "renders sequences, job files and Slurm job arrays.\n"
  "\n"
  "This package holds the vdb_ewa command, the shared library libvdb_ewa with\n"
  "its headers and CMake package (find_package(vdb_ewa)), and the Python module\n"
  "vdb_ewa for Debian's python3, which Blender's vdb_ewa add-on imports.")
# Depends: the libraries the binaries link (dpkg-shlibdeps, from dpkg-dev), and the Python the
# module was built for (a cpython-3XY extension) with numpy (its arrays).
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_GENERATE_SHLIBS ON) # shlibs, and an ldconfig trigger
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
if(VDB_EWA_HAVE_PYTHON)
  math(EXPR _vdb_ewa_python_next "${Python_VERSION_MINOR} + 1")
  set(CPACK_DEBIAN_PACKAGE_DEPENDS
    "python3 (>= ${Python_VERSION_MAJOR}.${Python_VERSION_MINOR}~), python3 (<< ${Python_VERSION_MAJOR}.${_vdb_ewa_python_next}), python3-numpy")
endif()
# What building against the headers and the CMake package needs (find_package(vdb_ewa) finds glm;
# COMPONENTS OpenVDB, OpenVDB and TBB).
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "libglm-dev, libopenvdb-dev, libtbb-dev, blender")
set(CPACK_SOURCE_IGNORE_FILES "/\\\\.git/" "/build[^/]*/")
include(CPack)
