// fdsurf: the command-line tool. Every command validates its whole input
// before it writes anything, so an error leaves stdout empty.
#include <CLI/CLI.hpp>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "fdsurf/host/fixed_engine.h"
#include "fdsurf/host/patch_io.h"
#include "fdsurf/host/quantum.h"
#include "fdsurf/host/reference.h"

namespace fdsurf::host {
namespace {

struct Grid {
  int steps_s = 0;
  int steps_t = 0;
};

Grid ParseGrid(const std::string& text) {
  const auto fail = [&](const std::string& why) {
    return InputError("--grid: '" + text + "' " + why);
  };
  const std::size_t x = text.find('x');
  const auto parse = [&](std::string_view part) {
    int value = 0;
    const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), value);
    if (part.empty() || ec != std::errc() || end != part.data() + part.size()) {
      throw fail("is not N or NxM with whole numbers N, M");
    }
    if (value < 1 || value > kMaxPatchSteps) {
      throw fail("is out of range: each dimension must be between 1 and " +
                 std::to_string(kMaxPatchSteps));
    }
    return value;
  };
  const std::string_view all(text);
  Grid grid;
  grid.steps_s = parse(all.substr(0, x));
  grid.steps_t = x == std::string::npos ? grid.steps_s : parse(all.substr(x + 1));
  return grid;
}

struct SampleOptions {
  std::string file;
  std::string grid;
  std::string engine = "fixed";
  std::string quantum = "0.001";
};

// Buffered stdout writer; CSV rows are many and small.
class Output {
 public:
  Output() { buffer_.reserve(1 << 16); }
  ~Output() { Flush(); }
  Output(const Output&) = delete;
  Output& operator=(const Output&) = delete;
  void Append(const std::string& s) {
    buffer_ += s;
    if (buffer_.size() > (1 << 16)) Flush();
  }
  void Flush() {
    std::fwrite(buffer_.data(), 1, buffer_.size(), stdout);
    buffer_.clear();
  }

 private:
  std::string buffer_;
};

std::string FormatDouble(double v) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

int RunSample(const SampleOptions& options) {
  const Grid grid = ParseGrid(options.grid);
  const Quantum quantum = Quantum::Parse(options.quantum);
  const PatchSet set = ReadPatchFile(options.file);
  const bool fixed = options.engine == "fixed";
  std::vector<PreparedPatch<3>> prepared;
  if (fixed) {
    prepared.reserve(set.patches.size());
    for (const Patch& patch : set.patches) {
      prepared.push_back(PrepareFixedPatch(patch, quantum, grid.steps_s, grid.steps_t));
    }
  }
  Output out;
  out.Append("patch,i,j,x,y,z\n");
  for (std::size_t p = 0; p < set.patches.size(); ++p) {
    const std::string prefix = std::to_string(p) + ",";
    if (fixed) {
      ForEachGridPoint(prepared[p],
                       [&](std::uint32_t i, std::uint32_t j, const std::int32_t(&q)[3]) {
                         out.Append(prefix + std::to_string(i) + "," + std::to_string(j) + "," +
                                    quantum.Format(q[0]) + "," + quantum.Format(q[1]) + "," +
                                    quantum.Format(q[2]) + "\n");
                       });
    } else {
      for (int i = 0; i <= grid.steps_s; ++i) {
        for (int j = 0; j <= grid.steps_t; ++j) {
          const Point3 v = EvaluateReference(set.patches[p], static_cast<double>(i) / grid.steps_s,
                                             static_cast<double>(j) / grid.steps_t);
          out.Append(prefix + std::to_string(i) + "," + std::to_string(j) + "," +
                     FormatDouble(v[0]) + "," + FormatDouble(v[1]) + "," + FormatDouble(v[2]) +
                     "\n");
        }
      }
    }
  }
  return 0;
}

int RunCheck(const SampleOptions& options) {
  const Grid grid = ParseGrid(options.grid);
  const Quantum quantum = Quantum::Parse(options.quantum);
  const PatchSet set = ReadPatchFile(options.file);
  std::vector<PreparedPatch<3>> prepared;
  for (const Patch& patch : set.patches) {
    prepared.push_back(PrepareFixedPatch(patch, quantum, grid.steps_s, grid.steps_t));
  }
  const double q = quantum.value();
  const std::string units = set.units.empty() ? "file units" : set.units;
  double worst = 0;
  std::size_t worst_patch = 0;
  std::printf("grid %dx%d, quantum %s %s, bound 0.51 quanta\n", grid.steps_s, grid.steps_t,
              quantum.Format(1).c_str(), units.c_str());
  std::printf("patch  acc  frac  exact  max error (quanta)  max error (%s)  at (i,j)\n",
              units.c_str());
  for (std::size_t p = 0; p < set.patches.size(); ++p) {
    double patch_worst = 0;
    std::uint32_t at_i = 0;
    std::uint32_t at_j = 0;
    ForEachGridPoint(prepared[p], [&](std::uint32_t i, std::uint32_t j, const std::int32_t(&k)[3]) {
      const Point3 exact = EvaluateReference(set.patches[p], static_cast<double>(i) / grid.steps_s,
                                             static_cast<double>(j) / grid.steps_t);
      for (int c = 0; c < 3; ++c) {
        const double error = std::fabs(k[c] - quantum.ToQuanta(exact[c]));
        if (error > patch_worst) {
          patch_worst = error;
          at_i = i;
          at_j = j;
        }
      }
    });
    std::printf("%5zu  %3d  %4d  %5s  %18.6f  %*.3g  (%u,%u)\n", p, prepared[p].format.acc_bits,
                prepared[p].format.frac_bits, prepared[p].exact ? "yes" : "no", patch_worst,
                static_cast<int>(units.size()) + 13, patch_worst * q, at_i, at_j);
    if (patch_worst > worst) {
      worst = patch_worst;
      worst_patch = p;
    }
  }
  std::printf("overall: max error %.6f quanta (%.3g %s) in patch %zu, %zu patches: %s\n", worst,
              worst * q, units.c_str(), worst_patch, set.patches.size(),
              worst <= 0.51 ? "within the 0.51-quantum bound" : "BOUND VIOLATED");
  return worst <= 0.51 ? 0 : 1;
}

void AddCommonOptions(CLI::App* command, SampleOptions* options) {
  command->add_option("FILE", options->file, "patch file (.bpt or .json, see docs/formats.md)")
      ->required();
  command
      ->add_option("--grid", options->grid,
                   "steps per patch: N (NxN) or NxM, each 1.." + std::to_string(kMaxPatchSteps))
      ->required();
  command
      ->add_option("--quantum", options->quantum,
                   "output quantum Q in file units; positions are whole multiples of Q")
      ->capture_default_str();
}

int Main(int argc, char** argv) {
  CLI::App app{
      "fdsurf: bicubic patches evaluated by fixed-point forward differences, with a proven "
      "0.51-quantum error bound."};
  app.require_subcommand(1);

  SampleOptions sample_options;
  CLI::App* sample = app.add_subcommand(
      "sample",
      "Print every grid point of every patch as CSV: patch,i,j,x,y,z (s = i/N, t = j/M).");
  AddCommonOptions(sample, &sample_options);
  sample
      ->add_option("--engine", sample_options.engine,
                   "fixed: forward differences, exact multiples of Q; double: the reference")
      ->check(CLI::IsMember({"fixed", "double"}))
      ->capture_default_str();

  SampleOptions check_options;
  CLI::App* check = app.add_subcommand(
      "check", "Compare the fixed engine with the double reference on every grid point.");
  AddCommonOptions(check, &check_options);

  // CLI11 would only say "a subcommand is required" for a mistyped command.
  if (argc > 1 && argv[1][0] != '-' && std::string(argv[1]) != "sample" &&
      std::string(argv[1]) != "check") {
    std::fprintf(stderr, "fdsurf: error: unknown command '%s' (expected sample or check)\n",
                 argv[1]);
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (sample->parsed()) return RunSample(sample_options);
    if (check->parsed()) return RunCheck(check_options);
  } catch (const InputError& e) {
    std::fprintf(stderr, "fdsurf: error: %s\n", e.what());
    return 2;
  } catch (const EngineError& e) {
    std::fprintf(stderr, "fdsurf: error: %s\n", e.what());
    return 3;
  }
  return 1;
}

}  // namespace
}  // namespace fdsurf::host

int main(int argc, char** argv) {
  try {
    return fdsurf::host::Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fdsurf: internal error: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "fdsurf: internal error\n");
  }
  return 4;
}
