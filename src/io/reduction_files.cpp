// A reduced model's files in an output folder: io/reduction_files.hpp.
#include "rubdyn/io/reduction_files.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "rubdyn/io/matrix_files.hpp"
#include "rubdyn/io/model_registry.hpp"
#include "rubdyn/io/text_files.hpp"

namespace rubdyn {

namespace {

std::string json_num(double x) {
  return std::isfinite(x) ? fmt::format("{}", x) : std::string("null");
}

/// Removes the regular files `names` of the folder (an earlier run's: `what` says which).
template <class Names>
void remove_stale(int dir_fd, const std::string& dir, const Names& names, const char* what) {
  for (const char* name : names) {
    struct stat st {};
    if (::fstatat(dir_fd, name, &st, AT_SYMLINK_NOFOLLOW) != 0 || !S_ISREG(st.st_mode)) continue;
    if (::unlinkat(dir_fd, name, 0) != 0 && errno != ENOENT)
      throw std::runtime_error(fmt::format("cannot remove {}/{} (of an earlier {}): {}", dir, name,
                                           what, std::strerror(errno)));
  }
}

}  // namespace

void write_output_modes_files(int dir_fd, const std::string& dir, const CaseSpec& spec) {
  const int count = spec.model == "matrices" ? spec.matrices.output_modes : 0;
  if (count <= 0) {
    remove_stale(dir_fd, dir, kOutputModesFiles, "run with output.modes");
    return;
  }
  const MatrixParams p = matrix_model_params(spec);  // (the reduced model with a [reduction])
  const RotorModes modes = rotor_modes(p, count);
  const auto put = [&](const char* name, const std::string& bytes) {
    write_file_at(dir_fd, name, dir + "/" + name, bytes);
  };
  put("output_modes.npy", npy_bytes(modes.shapes));
  const MatrixRotorParams& r = p.rotor;
  const int n = r.size();
  std::string j = "{\n";
  j += fmt::format("  \"count\": {},\n", count);
  j += fmt::format("  \"model\": \"{}\",\n", matrix_reduction(spec) ? "reduced" : "full");
  j += fmt::format("  \"size\": {},\n", n);
  j += fmt::format("  \"isotropic\": {},\n", modes.isotropic ? "true" : "false");
  std::string f, planes, names;
  for (int k = 0; k < count; ++k) {
    if (k) f.append(", "), planes.append(", ");
    f.append(json_num(modes.f_hz[static_cast<std::size_t>(k)]));
    planes.append(quoted_string(modes.planes[static_cast<std::size_t>(k)]));
  }
  for (int i = 0; i < n; ++i) {
    if (i) names.append(", ");
    names.append(quoted_string(static_cast<int>(r.names.size()) == n
                                   ? r.names[static_cast<std::size_t>(i)]
                                   : fmt::format("q{}", i)));
  }
  j.append("  \"frequencies_hz\": [").append(f).append("],\n");
  j.append("  \"planes\": [").append(planes).append("],\n");
  j.append("  \"coordinates\": [").append(names).append("],\n");
  j += fmt::format(
      "  \"definition\": {}\n}}\n",
      quoted_string(fmt::format(
          "timeseries.csv's mode<k> is eta_k = phi_k^T M q and vmode<k> its rate phi_k^T M q', "
          "phi_k the k-th column of output_modes.npy: the {} lowest free modes (K phi = w^2 M "
          "phi, undamped, at rest) of the {} rotor's M and K ({} coordinates q, the rows of the "
          "shapes), mass-normalised (phi^T M phi = 1), each with its largest entry positive{}",
          count, matrix_reduction(spec) ? "reduced" : "full", n,
          modes.isotropic ? "; isotropic: computed on the x plane, in (x, y) pairs of one "
                            "frequency"
                          : "")));
  put("output_modes.json", j);
}

void write_reduction_files(int dir_fd, const std::string& dir, const CaseSpec& spec) {
  const auto red = matrix_reduction(spec);
  if (!red) {
    remove_stale(dir_fd, dir, kReductionFiles, "reduced run");
    return;
  }
  const auto put = [&](const char* name, const std::string& bytes) {
    write_file_at(dir_fd, name, dir + "/" + name, bytes);
  };
  const MatrixRotorParams& r = red->rotor;
  put("reduced_M.npy", npy_bytes(r.M));
  put("reduced_C.npy", npy_bytes(r.C));
  put("reduced_K.npy", npy_bytes(r.K));
  put("reduced_G.npy", npy_bytes(r.G));
  put("reduced_f0.npy", npy_bytes(r.f0, true));
  put("reduced_T.npy", npy_bytes(red->T));
  put("reduced_modes.npy", npy_bytes(red->modes));
  std::string j = "{\n";
  j +=
      fmt::format("  \"method\": {},\n", quoted_string(std::string(to_string(red->params.method))));
  j += fmt::format("  \"modes\": {},\n",
                   red->params.modes > 0 ? std::to_string(red->params.modes) : "null");
  j += fmt::format("  \"cutoff_hz\": {},\n",
                   red->params.modes > 0 ? "null" : json_num(red->params.cutoff));
  j +=
      fmt::format("  \"full_size\": {},\n  \"reduced_size\": {},\n", red->full_size, red->T.cols());
  j += fmt::format("  \"isotropic\": {},\n", red->isotropic ? "true" : "false");
  const int m = static_cast<int>(red->T.cols());
  const int nm = static_cast<int>(red->f_hz.size());
  std::string names, phys;
  for (int i = 0; i < m; ++i) {
    // (appended, not "..." + string: g++ 12 warns falsely, -Wrestrict)
    if (i) names.append(", ");
    names.append(quoted_string(r.names[static_cast<std::size_t>(i)]));
    if (i < m - nm)  // the full coordinate that p_i is (its index into q)
      phys += fmt::format("{}{}: {}", phys.empty() ? "" : ", ",
                          quoted_string(r.names[static_cast<std::size_t>(i)]),
                          red->physical[static_cast<std::size_t>(i)]);
  }
  j.append("  \"coordinates\": [").append(names).append("],\n");
  j.append("  \"physical\": {").append(phys).append("},\n");
  std::string f, planes;
  for (int k = 0; k < nm; ++k) {
    if (k) f.append(", "), planes.append(", ");
    f.append(json_num(red->f_hz[static_cast<std::size_t>(k)]));
    planes.append(quoted_string(red->mode_planes[static_cast<std::size_t>(k)]));
  }
  j.append("  \"modes_hz\": [").append(f).append("],\n");
  j.append("  \"mode_planes\": [").append(planes).append("],\n");
  j += fmt::format("  \"next_mode_hz\": {},\n", json_num(red->f_next));
  j += fmt::format("  \"description\": {}\n}}\n", quoted_string(red->describe()));
  put("reduction.json", j);
}

}  // namespace rubdyn
