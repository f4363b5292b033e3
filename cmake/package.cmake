# The installable C++ package (`cmake --install build --prefix P`):
#   P/lib/liblash.so, P/lib/liblash.a   every layer but the command line (core, analysis, io,
#                                       study, sweep, report) in one library, built both ways from the
#                                       same position-independent objects as the component
#                                       libraries (nothing is compiled twice)
#   P/include/lash/<layer>/*.hpp        the headers, as they lie under src/
#   P/bin/lash, P/bin/lash-mpi          the command (lash-mpi: with MPI, when built)
#   P/share/lash/lash_figures.py        the figures tool (found relative to the binary)
#   P/lib/cmake/Lash/                   LashConfig.cmake, its version file and the exported
#                                       targets Lash::lash (shared) and Lash::lash_static
# Headers include each other as "core/x.hpp", so both include/lash (for those includes) and
# include (for a user's <lash/core/x.hpp>) are on the targets' include path.
include(CMakePackageConfigHelpers)

set(LASH_COMPONENTS lash_core lash_analysis lash_io lash_study lash_sweep lash_report lash_report_assets)
set(LASH_OBJECTS "")
foreach(c ${LASH_COMPONENTS})
  list(APPEND LASH_OBJECTS $<TARGET_OBJECTS:${c}>)
endforeach()

# Libraries a program using Lash links besides it: the public headers include Eigen, fmt and
# nlohmann-json; the others are the implementation's.
set(LASH_PRIVATE_LIBS yaml-cpp ${MUPARSER_LIB} ${GINAC_LIB} ${CLN_LIB} ${SUNDIALS_LIBS}
                      ${FFTW3_THREADS_LIB} ${FFTW3_LIB} SQLite::SQLite3)
if(LASH_HDF5)
  list(APPEND LASH_PRIVATE_LIBS ${HDF5_SERIAL_LIB})
endif()
# The same by name for the static library's users (no paths of this machine in installed files).
set(LASH_STATIC_LINK yaml-cpp muparser ginac cln sundials_cvode sundials_nvecserial
                     sundials_sunmatrixdense sundials_sunlinsoldense fftw3_threads fftw3 sqlite3
                     Threads::Threads)
if(LASH_HDF5)
  list(APPEND LASH_STATIC_LINK hdf5_serial)
endif()

foreach(kind shared static)
  string(TOUPPER ${kind} KIND)
  set(t lash_${kind})
  add_library(${t} ${KIND} ${LASH_OBJECTS})
  set_target_properties(${t} PROPERTIES OUTPUT_NAME lash VERSION ${PROJECT_VERSION}
                                        SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR})
  target_include_directories(${t} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/src>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/lash>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_compile_features(${t} PUBLIC cxx_std_17)
  target_link_libraries(${t} PUBLIC Eigen3::Eigen nlohmann_json::nlohmann_json fmt::fmt
                                    Threads::Threads)
endforeach()
set_target_properties(lash_shared PROPERTIES EXPORT_NAME lash)
set_target_properties(lash_static PROPERTIES EXPORT_NAME lash_static)
target_link_libraries(lash_shared PRIVATE ${LASH_PRIVATE_LIBS})
foreach(lib ${LASH_STATIC_LINK})
  target_link_libraries(lash_static PUBLIC $<LINK_ONLY:${lib}>)
endforeach()

install(TARGETS lash_shared lash_static EXPORT LashTargets
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(TARGETS ${LASH_PROGRAMS} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY src/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/lash
        FILES_MATCHING PATTERN "*.hpp" PATTERN "cli" EXCLUDE)
install(FILES tools/lash_figures.py DESTINATION ${CMAKE_INSTALL_DATADIR}/lash)
# The documentation the program's messages cite (docs/model-format.md, ...), laid out as in the
# source so that README.md's links hold: share/doc/lash/README.md and share/doc/lash/docs/.
install(FILES README.md DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/lash)
install(DIRECTORY docs/ DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/lash/docs)
install(EXPORT LashTargets NAMESPACE Lash:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/Lash)
configure_package_config_file(cmake/LashConfig.cmake.in
  ${PROJECT_BINARY_DIR}/LashConfig.cmake INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/Lash)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/LashConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/LashConfig.cmake ${PROJECT_BINARY_DIR}/LashConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/Lash)
