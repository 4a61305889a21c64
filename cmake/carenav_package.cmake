# `cpack -G DEB` in the build folder: a Debian package of the installed tree
# (bin/carenav, share/carenav, share/doc/carenav). Its dependencies are the
# Debian runtime packages of the shared libraries the binary links (MRPT's
# among them), as dpkg-shlibdeps finds them; MRPT's datasets (the demo's SENA
# rawlog) are recommended.
set(CPACK_PACKAGE_NAME carenav)
set(CPACK_PACKAGE_VENDOR "The carenav authors")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "Mapping, localisation and navigation for assistive indoor robots, on MRPT")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_RESOURCE_FILE_LICENSE ${PROJECT_SOURCE_DIR}/LICENSE)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_GENERATOR DEB)
set(CPACK_DEBIAN_PACKAGE_MAINTAINER "The carenav authors")
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "mrpt-common")
set(CPACK_DEBIAN_PACKAGE_DESCRIPTION
    "Headless command-line suite for robotic walkers, social and care robots:\n\
ICP and RBPF SLAM over MRPT rawlogs and CARMEN logs, Monte Carlo localisation,\n\
3D-to-2D obstacle projection with ground-plane detection, reactive navigation\n\
with a safety supervisor, rooms and places on maps, and a simulator.")
include(CPack)
