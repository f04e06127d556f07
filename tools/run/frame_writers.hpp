#pragma once
// stabint-run's per-frame output: the CSV of energies and timings, OBJ meshes and a VTK time
// series. Every write is checked, so that a full disk or a closed file ends the run with an error.
#include "cli.hpp"

#include <stabint/stabint.hpp>

#include <array>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

namespace stabint_run {

// The directory `dir` of the option `flag`, made with its parents where missing; a path that is
// a file or cannot be made is a usage error naming the option.
inline void makeOutputDirectory(const char* flag, const std::string& dir) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (!error && !std::filesystem::is_directory(dir, error)) error = std::make_error_code(std::errc::not_a_directory);
  if (error) throw UsageError(std::string(flag) + ": cannot make the directory '" + dir + "': " + error.message());
}

class ObjWriter {
 public:
  ObjWriter(std::string dir, const stabint::Scene& scene) : dir_(std::move(dir)) {
    makeOutputDirectory("--obj-dir", dir_);
    triangles_ = scene.triangles.empty() ? stabint::tetSurface(scene.tets) : scene.triangles;
    if (triangles_.empty()) {
      for (const stabint::Spring& s : scene.springs) lines_.push_back({s.a, s.b});
    }
  }

  void write(int frame, const Eigen::MatrixX3d& x) const {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%05d.obj", frame);
    const std::string path = (std::filesystem::path(dir_) / name).string();
    std::ofstream out(path);
    if (!out) throw UsageError("--obj-dir: cannot write " + path);
    char line[96];
    for (Eigen::Index i = 0; i < x.rows(); ++i) {
      std::snprintf(line, sizeof(line), "v %.9g %.9g %.9g\n", x(i, 0), x(i, 1), x(i, 2));
      out << line;
    }
    for (const auto& t : triangles_) out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
    for (const auto& l : lines_) out << "l " << l[0] + 1 << ' ' << l[1] + 1 << '\n';
    out.close();  // the last buffer is written here: a full disk shows only now
    if (!out) throw UsageError("--obj-dir: write failed for " + path + writeErrorText());
  }

 private:
  std::string dir_;
  std::vector<std::array<int, 3>> triangles_;
  std::vector<std::array<int, 2>> lines_;
};

// A VTK time series (--vtk DIR) for ParaView, written without the VTK library: one XML
// UnstructuredGrid file per written frame (DIR/frame_00000.vtu, ...) and DIR/frames.pvd, the
// collection that lists each file with its time. ASCII with 17 significant digits, so that a
// reader (meshio, ParaView) gets the simulator's doubles back to the last bit; binary would be
// smaller, but the OBJ frames are text too and a series this tool writes is for looking at.
// Cells: the tets (volume), else the surface triangles, else the springs as lines, else one
// vertex per particle, so that every scene shows something.
class VtkWriter {
 public:
  VtkWriter(std::string dir, const stabint::Scene& scene) : dir_(std::move(dir)) {
    makeOutputDirectory("--vtk", dir_);
    // VTK cell types: 10 tetra, 5 triangle, 3 line, 1 vertex.
    if (!scene.tets.empty()) {
      for (const stabint::Tet& t : scene.tets) addCell(10, t.vertices);
    } else if (!scene.triangles.empty()) {
      for (const auto& t : scene.triangles) addCell(5, t);
    } else if (!scene.springs.empty()) {
      for (const stabint::Spring& s : scene.springs) addCell(3, std::array<int, 2>{s.a, s.b});
    } else {
      for (int i = 0; i < scene.numParticles(); ++i) addCell(1, std::array<int, 1>{i});
    }
  }

  void write(int frame, double time, const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& v) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%05d.vtu", frame);
    const std::string path = (std::filesystem::path(dir_) / name).string();
    errno = 0;
    std::ofstream out(path);
    if (!out) throw UsageError("--vtk: cannot write " + path + writeErrorText());
    const auto rows = [&out](const Eigen::MatrixX3d& m) {
      char line[96];
      for (Eigen::Index i = 0; i < m.rows(); ++i) {
        std::snprintf(line, sizeof(line), "%.17g %.17g %.17g\n", m(i, 0), m(i, 1), m(i, 2));
        out << line;
      }
    };
    out << "<?xml version=\"1.0\"?>\n"
           "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
           "header_type=\"UInt64\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\""
        << x.rows() << "\" NumberOfCells=\"" << types_.size()
        << "\">\n<PointData Vectors=\"velocity\">\n"
           "<DataArray type=\"Float64\" Name=\"velocity\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    rows(v);
    out << "</DataArray>\n</PointData>\n<Points>\n"
           "<DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    rows(x);
    out << "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
    for (int i : connectivity_) out << i << '\n';
    out << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
    for (int i : offsets_) out << i << '\n';
    out << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
    for (int i : types_) out << i << '\n';
    out << "</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
    out.close();  // a full disk shows only now
    if (!out) throw UsageError("--vtk: write failed for " + path + writeErrorText());
    frames_.emplace_back(time, name);
  }

  // The collection, written once at the end of the run (also after a blow-up or a signal, with
  // the frames written so far), so that it never lists a file that was not written.
  void finish() const {
    const std::string path = (std::filesystem::path(dir_) / "frames.pvd").string();
    errno = 0;
    std::ofstream out(path);
    out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
           "<Collection>\n";
    char line[128];
    for (const auto& [time, file] : frames_) {
      std::snprintf(line, sizeof(line), "<DataSet timestep=\"%.17g\" group=\"\" part=\"0\" file=\"%s\"/>\n", time,
                    file.c_str());
      out << line;
    }
    out << "</Collection>\n</VTKFile>\n";
    out.close();
    if (!out) throw UsageError("--vtk: write failed for " + path + writeErrorText());
  }

 private:
  template <size_t N>
  void addCell(int type, const std::array<int, N>& vertices) {
    connectivity_.insert(connectivity_.end(), vertices.begin(), vertices.end());
    offsets_.push_back(static_cast<int>(connectivity_.size()));
    types_.push_back(type);
  }

  std::string dir_;
  std::vector<int> connectivity_, offsets_, types_;
  std::vector<std::pair<double, std::string>> frames_;
};

// --csv: the library's CsvReporter (stabint/reporters.hpp) writes the format, checks and flushes
// every row, so that a full disk (--csv /dev/full) or a closed file ends the run with an error
// naming the option, not exit 0 with nothing written. The run writes the rows itself rather
// than attaching it: besides every --every-th frame it writes frame 0, the last frame and the
// last finite frame of a blow-up.
class CsvWriter {
  template <class Write>
  static decltype(auto) named(Write&& write) {
    try {
      return write();
    } catch (const stabint::FileFormatError& e) {
      throw UsageError(std::string("--csv: ") + e.what());
    }
  }

 public:
  explicit CsvWriter(const std::string& path)
      : csv_(named([&] {
          return path == "-" ? std::make_unique<stabint::CsvReporter>(std::cout, "standard output")
                             : std::make_unique<stabint::CsvReporter>(path);
        })) {}

  void row(int frame, const stabint::StepReport& r) {
    named([&] { csv_->row(frame, r); });
  }
  void initialRow(const stabint::Simulator& sim) {
    named([&] { csv_->initialRow(sim); });
  }

 private:
  std::unique_ptr<stabint::CsvReporter> csv_;
};

}  // namespace stabint_run
