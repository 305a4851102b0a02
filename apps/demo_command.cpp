// `plsa demo`: the README's main job. At this stage of the project it fits the
// single-region DIO-OBF model to the real soft-arm trials and validates it
// leave-one-trial-out; the full DIO-PWL-OBF pipeline replaces it (issue 4).
#include <algorithm>
#include <cmath>
#include <memory>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "plsa/eval/dio_prediction.hpp"
#include "plsa/identify/linear_dio_obf.hpp"
#include "plsa/io/csv_log.hpp"

namespace fs = std::filesystem;

namespace plsa::app {
namespace {

struct DemoOptions {
  std::string data_dir = std::string(PLSA_DEFAULT_DATA_DIR) + "/softarm-bruder2021";
  std::string out_dir = "plsa-demo";
};

// Paper Table II, u1->y1, identified at 80 Hz; mapped to the log's rate by p^(T/T80).
std::vector<double> tableTwoPoles(double sample_time) {
  std::vector<double> out;
  for (double p : {0.981, 0.969, 0.964, 0.957, 0.945}) out.push_back(std::pow(p, sample_time * 80.0));
  return out;
}

void runDemo(const DemoOptions& opt) {
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(opt.data_dir))
    if (e.path().extension() == ".csv") files.push_back(e.path().string());
  std::sort(files.begin(), files.end());
  if (files.size() < 2)
    throw std::runtime_error(opt.data_dir + ": need at least two trial CSV files for leave-one-out");
  const std::vector<std::string> inputs = {"u_1", "u_2", "u_3"};
  const std::vector<std::string> outputs = {"y_1", "y_2"};
  io::CsvReadOptions read_opt;
  read_opt.required = {"time_s", "u_1", "u_2", "u_3", "y_1", "y_2"};

  std::printf("plsa demo: real-data check on %zu trials from %s\n", files.size(), opt.data_dir.c_str());
  std::vector<Eigen::MatrixXd> U, Y;
  double sample_time = 0.0;
  for (const auto& f : files) {
    const io::Log log = io::readCsvLog(f, read_opt);
    // One dropped sample is tolerated (a gap under 2.5 periods); a longer gap is an error.
    sample_time = io::checkedSampleTime(log, "time_s", 2.5);
    U.push_back(log.columnsOf(inputs));
    Y.push_back(log.columnsOf(outputs));
  }
  const std::vector<double> poles = tableTwoPoles(sample_time);
  std::printf("  model: single-region DIO-OBF, 5 real poles per input (paper Table II mapped to %.4f s):",
              sample_time);
  for (double p : poles) std::printf(" %.3f", p);
  std::printf("\n  validation: leave-one-trial-out, NRMSE fit %% (100 = perfect)\n");

  const int horizon_long = static_cast<int>(std::lround(1.0 / sample_time));
  const std::vector<PoleSet> pole_sets(inputs.size(), PoleSet::real(poles));
  fs::create_directories(opt.out_dir);
  const std::string csv_path = (fs::path(opt.out_dir) / "demo_fits.csv").string();
  std::ofstream csv(csv_path);
  csv << "held_out,output,fit_k1,fit_k" << horizon_long << ",fit_sim\n";
  std::printf("  %-14s %-6s %8s %8s %8s\n", "held-out", "output", "1-step",
              (std::to_string(horizon_long) + "-step").c_str(), "sim");
  Eigen::MatrixXd sums = Eigen::MatrixXd::Zero(outputs.size(), 3);
  for (std::size_t hold = 0; hold < files.size(); ++hold) {
    std::vector<Eigen::MatrixXd> Ut, Yt;
    for (std::size_t r = 0; r < files.size(); ++r)
      if (r != hold) {
        Ut.push_back(U[r]);
        Yt.push_back(Y[r]);
      }
    const LinearDioObf model = LinearDioObf::fit(pole_sets, Ut, Yt);
    const Eigen::MatrixXd dyhat = model.increments(U[hold]);
    for (std::size_t o = 0; o < outputs.size(); ++o) {
      const Eigen::VectorXd y = Y[hold].col(static_cast<Eigen::Index>(o));
      const Eigen::VectorXd d = dyhat.col(static_cast<Eigen::Index>(o));
      const double f1 = fitOf(y, kStepAhead(y, d, 1));
      const double fk = fitOf(y, kStepAhead(y, d, horizon_long));
      const double fs_ = fitOf(y, simulate(y, d));
      sums.row(static_cast<Eigen::Index>(o)) += Eigen::RowVector3d(f1, fk, fs_);
      const std::string name = fs::path(files[hold]).stem().string();
      std::printf("  %-14s %-6s %8.1f %8.1f %8.1f\n", name.c_str(), outputs[o].c_str(), f1, fk, fs_);
      csv << name << "," << outputs[o] << "," << f1 << "," << fk << "," << fs_ << "\n";
    }
  }
  sums /= static_cast<double>(files.size());
  for (std::size_t o = 0; o < outputs.size(); ++o)
    std::printf("  %-14s %-6s %8.1f %8.1f %8.1f\n", "mean", outputs[o].c_str(), sums(o, 0), sums(o, 1), sums(o, 2));
  std::printf("  wrote %s\n", csv_path.c_str());
  std::printf("  not yet in this build: simulated actuator, PWL scheduling, FKcM poles (issues 3, 4)\n");
}

}  // namespace

void addDemoCommand(CLI::App& app) {
  auto opt = std::make_shared<DemoOptions>();
  CLI::App* cmd = app.add_subcommand("demo", "Run the main job and print what it did");
  cmd->add_option("--data", opt->data_dir, "Folder of real trial CSVs (u_1..u_3, y_1, y_2)");
  cmd->add_option("--out", opt->out_dir, "Folder for the results");
  cmd->callback([opt] { runDemo(*opt); });
}

}  // namespace plsa::app
