# Finds PCL. Debian 12's VTK 9.1 package config (pulled in by PCL's io component) references
# MPI::MPI_C through VTK::mpi even when no MPI is installed, which makes CMake's generate step
# fail. heatcvt never links VTK; when MPI is absent we define an empty MPI::MPI_C so that
# the reference resolves.
find_package(MPI QUIET COMPONENTS C)
if(NOT TARGET MPI::MPI_C)
  add_library(MPI::MPI_C INTERFACE IMPORTED)
endif()
find_package(PCL 1.10 REQUIRED COMPONENTS common io kdtree search features filters surface)
