#!/usr/bin/env bash
# The one list of Debian packages thorax needs. Installs what is missing;
# idempotent, and silent when everything is already there.
set -euo pipefail
packages=(
  build-essential cmake pkg-config   # compiler and build
  clang libclang-rt-14-dev           # make fuzz: libFuzzer with ASan/UBSan (scripts/fuzz.sh)
  libcjson-dev                       # model.json manifest
  libgmp-dev                         # tests: exact rational reference for the predicates
  libmatio-dev                       # MATLAB .mat time series (libmatio)
  zlib1g-dev                         # import: zlib-compressed VTK XML (.vtu) data
  petsc-dev openmpi-bin              # finite-element solves: PETSc 3.18 (hypre, MUMPS, CHOLMOD) on Open MPI; mpirun
  paraview-dev                       # sort-last compositing over MPI ranks: IceT (ParaView 5.11's; headers here, libraries in paraview); optional at build
  libsuitesparse-dev                 # CHOLMOD, which the solver module drives itself for many right-hand sides
  libopenblas0-pthread               # optimized BLAS for the sparse Cholesky factorizations (4-9x over reference BLAS)
  liblapack-dev libblas-dev          # dense algebra: -llapack -lblas (BEM dgetrf/dgetrs; inverse dgesdd, dsyevd, dposv; OpenBLAS behind them)
  libepoxy-dev libegl-dev libegl-mesa0 libgl1-mesa-dri  # rendering: OpenGL 3.3 core on EGL (Mesa llvmpipe headless)
  libpng-dev libfreetype-dev libfontconfig-dev fonts-dejavu-core  # PNG images; text in images
  ffmpeg                             # animations: MP4 (H.264); ffprobe in tests
  libgtk-4-dev                       # thorax view: the interactive viewer (GTK 4, GtkGLArea)
  xvfb xauth xdotool x11-apps        # viewer tests under Xvfb (real key and mouse events, xwd); VTK beside ours
  python3-scipy                      # tests: scipy.io.loadmat reads our .mat files
  python3 python3-vtk9 python3-numpy # tests: VTK itself reads our exports
  gmsh python3-gmsh                  # tests: Gmsh itself reads our .msh volume exports (API, or the CLI)
  time                               # bench: peak memory (/usr/bin/time -v)
  man-db groff-base                  # tests: man -l renders the man pages made from the help (e2e_install)
  tetgen qhull-bin                   # bench: peer Delaunay tetrahedralizers run beside ours
  libcgal-dev                        # bench: CGAL's Delaunay_triangulation_3 beside ours (bench/delaunay_cgal.cpp, g++); Mesh_3 on label maps (bench/image.sh)
  libnifti2-dev libniftiio-dev       # images: NIfTI-1/2 (.nii, .nii.gz) through nifti2_io (src/image/nifti.c)
  libgdcm-dev libgdcm-tools g++      # images: DICOM series through GDCM (src/image/dicom_gdcm.cc); gdcmimg/gdcmanon/gdcmconv/gdcmdump write the test series
  python3-nibabel                    # tests: nibabel reads and writes NIfTI beside us
  invesalius-examples                # tests: a real CT (InVesalius's Cranium.inv3)
  libembree-dev embree-tools         # ray tracing (RaySpray, src/raytrace): Embree 3; embree-tools' benchmark beside ours (bench/trace.sh)
  python3-opencv                     # bench: OpenCV's intelligent scissors (Mortensen & Barrett) beside our livewire (bench/digitize.sh)
  chromium firefox-esr               # tests: the web page opened in real browsers (headless; WebGL through SwiftShader and llvmpipe; puppeteer-core drives them)
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# the web page's viewer: scripts/web.sh bundles web/ with the pinned three.js and esbuild from npm. Node
# and npm are wanted as commands: a machine with another distribution of Node (one whose nodejs package
# carries npm and conflicts with Debian's) keeps it
command -v node >/dev/null 2>&1 && command -v npm >/dev/null 2>&1 || missing+=(nodejs npm)
[ ${#missing[@]} -eq 0 ] && exit 0
echo "deps: installing ${missing[*]}"
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
