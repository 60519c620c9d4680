# `cpack -G DEB` in a build folder: mbstorm_<version>_<arch>.deb holding what the install()
# rules put under /usr, the binary stripped, its library dependencies found by dpkg-shlibdeps
# (dpkg-dev). scripts/deb-check.sh builds, installs, tries and removes it.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME mbstorm)
set(CPACK_PACKAGE_CONTACT "mbstorm maintainers <maintainers@users.noreply.h-seed-c360dd58.example>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "Modbus TCP load tester, reference slave and fuzzer")
# CPack puts the summary first and indents these lines itself.
set(CPACK_PACKAGE_DESCRIPTION
    "mbstorm measures a Modbus TCP server's throughput and latency under closed- or
open-loop load over io_uring, serves a reference slave with fault injection,
and fuzzes servers for crashes, hangs and deviations from the specification.")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_SECTION net)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
# Directories the package creates get 0755, whatever the builder's umask.
set(CPACK_INSTALL_DEFAULT_DIRECTORY_PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ
    GROUP_EXECUTE WORLD_READ WORLD_EXECUTE)
include(CPack)
