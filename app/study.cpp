#include "app/study.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>

#include "app/session_reader.hpp"
#include "app/file_output.hpp"
#include "app/session_schema.hpp"
#include "app/session_teaching.hpp"
#include "app/study_metrics.hpp"
#include "app/table_text.hpp"
#include "robot/collision.hpp"
#include "robot/errors.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::app {
namespace {

std::optional<double> median(std::vector<double> values) {
  if (values.empty()) return std::nullopt;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

// A CSV field: quoted when it holds a separator or a quote.
std::string csvField(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  return quoted + "\"";
}

std::string csvNumber(double value) {
  if (!std::isfinite(value)) return "";
  std::ostringstream out;
  out.precision(9);
  out << value;
  return out.str();
}

std::string csvNumber(const std::optional<double>& value) { return value ? csvNumber(*value) : ""; }

// The robot a recording was made with: the built-in or file model if it still resolves, else
// the recorded URDF text (meshes resolved against the robot resources).
robot::RobotModel recordedRobot(const SessionReader& reader) {
  const SessionMetadata& meta = reader.metadata();
  try {
    const std::filesystem::path path = resolveRobotPath(meta.robot_name);
    if (std::filesystem::exists(path)) return robot::RobotModel::fromUrdfFile(path, meta.tip_link);
  } catch (const InputError&) {
    // Not a built-in name nor an existing file any more: fall back to the recorded text.
  }
  if (meta.robot_urdf.empty()) throw InputError("no robot description recorded");
  return robot::RobotModel::fromUrdfString(meta.robot_urdf, resourceDir() / "robots", meta.tip_link);
}

}  // namespace

KMeansResult kMeans(const Eigen::MatrixXd& points, const Eigen::MatrixXd& initial_centres, int max_iterations) {
  if (points.cols() == 0 || initial_centres.cols() == 0 || points.rows() != initial_centres.rows() ||
      points.rows() == 0 || max_iterations < 1 || !points.allFinite() || !initial_centres.allFinite()) {
    throw std::invalid_argument("kMeans: expected D x P points and D x k finite centres, P, k, D >= 1");
  }
  const Eigen::Index P = points.cols();
  const Eigen::Index k = initial_centres.cols();
  KMeansResult result;
  result.centres = initial_centres;
  result.labels.assign(static_cast<std::size_t>(P), -1);
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    bool changed = false;
    for (Eigen::Index p = 0; p < P; ++p) {
      Eigen::Index best = 0;
      (result.centres.colwise() - points.col(p)).colwise().squaredNorm().minCoeff(&best);
      auto& label = result.labels[static_cast<std::size_t>(p)];
      if (label != static_cast<int>(best)) {
        label = static_cast<int>(best);
        changed = true;
      }
    }
    result.iterations = iteration + 1;
    if (!changed) {
      result.converged = true;
      break;
    }
    Eigen::MatrixXd sums = Eigen::MatrixXd::Zero(points.rows(), k);
    Eigen::VectorXi counts = Eigen::VectorXi::Zero(k);
    for (Eigen::Index p = 0; p < P; ++p) {
      const int label = result.labels[static_cast<std::size_t>(p)];
      sums.col(label) += points.col(p);
      ++counts[label];
    }
    for (Eigen::Index c = 0; c < k; ++c) {
      if (counts[c] > 0) result.centres.col(c) = sums.col(c) / counts[c];
    }
  }
  result.sizes.assign(static_cast<std::size_t>(k), 0);
  result.inertia = 0.0;
  for (Eigen::Index p = 0; p < P; ++p) {
    const int label = result.labels[static_cast<std::size_t>(p)];
    ++result.sizes[static_cast<std::size_t>(label)];
    result.inertia += (points.col(p) - result.centres.col(label)).squaredNorm();
  }
  return result;
}

Eigen::MatrixXd pairwiseDistances(const Eigen::MatrixXd& points) {
  const Eigen::Index P = points.cols();
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(P, P);
  for (Eigen::Index i = 0; i < P; ++i) {
    for (Eigen::Index j = i + 1; j < P; ++j) d(i, j) = d(j, i) = (points.col(i) - points.col(j)).norm();
  }
  return d;
}

Eigen::MatrixXd classicalMds(const Eigen::MatrixXd& distances, int dimensions) {
  const Eigen::Index P = distances.rows();
  if (P == 0 || distances.cols() != P || dimensions < 1 || !distances.allFinite() ||
      (distances - distances.transpose()).cwiseAbs().maxCoeff() > 1e-9 * (1.0 + distances.cwiseAbs().maxCoeff())) {
    throw std::invalid_argument("classicalMds: expected a finite symmetric P x P distance matrix, dimensions >= 1");
  }
  // B = −½ J D² J, J = I − 11ᵀ/P: the Gram matrix of the centred configuration.
  const Eigen::MatrixXd squared = distances.array().square().matrix();
  const Eigen::MatrixXd J = Eigen::MatrixXd::Identity(P, P) - Eigen::MatrixXd::Constant(P, P, 1.0 / static_cast<double>(P));
  const Eigen::MatrixXd B = -0.5 * J * squared * J;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(0.5 * (B + B.transpose()));
  Eigen::MatrixXd coordinates = Eigen::MatrixXd::Zero(dimensions, P);
  // Eigen sorts eigenvalues increasingly: the largest come last.
  for (int d = 0; d < dimensions && d < P; ++d) {
    const Eigen::Index column = P - 1 - d;
    const double lambda = std::max(0.0, solver.eigenvalues()[column]);
    Eigen::VectorXd axis = solver.eigenvectors().col(column) * std::sqrt(lambda);
    Eigen::Index largest = 0;
    axis.cwiseAbs().maxCoeff(&largest);
    if (axis[largest] < 0.0) axis = -axis;
    coordinates.row(d) = axis.transpose();
  }
  return coordinates;
}

std::vector<AreaClusterSeeds> thesisClusterSeeds() {
  constexpr double h = std::numbers::pi / 2.0;
  constexpr double q = std::numbers::pi / 4.0;
  const auto posture = [](std::array<double, 6> values) { return Eigen::Map<const Eigen::VectorXd>(values.data(), 6).eval(); };
  AreaClusterSeeds left{0, {"L1", "L2", "L3"},
                        {posture({0, h, -h, -h, h, h}), posture({0, h, -h, -h, -h, -h}), posture({0, h, h, h, -h, h})}};
  AreaClusterSeeds right{1,
                         {"R1", "R2", "R3", "R4", "R5", "R6", "R7"},
                         {posture({0, h, h, -h, -h, h}), posture({0, h, -h, h, -h, -h}), posture({0, h, -h, h, h, h}),
                          posture({h, h, h, h, -h, h}), posture({h, h, -h, -h, -h, -h}), posture({h, h, -h, -h, h, h}),
                          posture({q, h, q, 0, -q, h})}};
  return {left, right};
}

std::vector<AreaClusterSeeds> loadClusterSeeds(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError("cluster seeds: cannot read '" + file.string() + "'");
  std::map<int, AreaClusterSeeds> by_area;
  std::string line;
  int line_number = 0;
  std::optional<Eigen::Index> joints;
  bool first_row = true;  // the header, if any, is the first line that is no comment
  while (std::getline(in, line)) {
    ++line_number;
    const std::string where = file.filename().string() + ":" + std::to_string(line_number);
    if (line_number == 1) app::prepareFirstLine(line, "cluster seeds " + file.filename().string());
    if (trimmed(line).empty() || trimmed(line)[0] == '#') continue;
    const auto fields = splitCommaFields(line);
    const bool header = first_row && !fields.empty() && fields[0] == "area";
    first_row = false;
    if (header) continue;
    if (fields.size() < 3) throw InputError("cluster seeds " + where + ": expected area,name,q1,...");
    int area = 0;
    try {
      std::size_t used = 0;
      area = std::stoi(fields[0], &used);
      if (used != fields[0].size() || area < 0) throw std::invalid_argument("area");
    } catch (const std::exception&) {
      throw InputError("cluster seeds " + where + ": expected an area index >= 0, got '" + printable(fields[0]) + "'");
    }
    if (fields[1].empty()) throw InputError("cluster seeds " + where + ": empty cluster name");
    Eigen::VectorXd q(static_cast<Eigen::Index>(fields.size() - 2));
    for (std::size_t i = 2; i < fields.size(); ++i) {
      const std::optional<double> value = parseDecimal(fields[i]);
      if (!value) throw InputError("cluster seeds " + where + ": '" + printable(fields[i]) + "' is not a finite number");
      if (std::abs(*value) > kLargestTableValue) {
        throw InputError("cluster seeds " + where + ": '" + printable(fields[i]) + "' is beyond ±1e6");
      }
      q[static_cast<Eigen::Index>(i - 2)] = *value;
    }
    if (joints && *joints != q.size()) {
      throw InputError("cluster seeds " + where + ": expected " + std::to_string(*joints) + " joint values, got " +
                       std::to_string(q.size()));
    }
    joints = q.size();
    auto& seeds = by_area[area];
    seeds.area = area;
    seeds.names.push_back(fields[1]);
    seeds.centres.push_back(q);
  }
  if (by_area.empty()) throw InputError("cluster seeds: '" + file.string() + "' holds no centre");
  std::vector<AreaClusterSeeds> seeds;
  for (auto& [area, entry] : by_area) seeds.push_back(std::move(entry));
  return seeds;
}

ParticipantResult analyseSession(const SessionReader& reader, double replay_interval) {
  ParticipantResult result;
  const SessionMetadata& meta = reader.metadata();
  result.file = reader.file().filename().string();
  result.participant = meta.participant.empty() ? reader.file().stem().string() : meta.participant;
  result.robot = meta.robot_name;
  result.robot_urdf = meta.robot_urdf;
  result.scene = meta.scene_name;
  result.closed_cleanly = !reader.meta("end_time_utc").empty();
  const auto [first_time, last_time] = reader.recordedTimeSpan();
  result.duration_s = last_time - first_time;

  // Each area's latest take; a RECORDING the session ended in taught nothing (session_teaching.hpp).
  for (const RecordedArea& area : readRecordedTeaching(reader, /*read_graph=*/false).areas) {
    if (!area.complete) continue;
    result.q_fixed[area.index] = area.q_fixed;
    result.samples += area.X.cols();
    ++result.areas;
  }

  // E_task over executed motions; shape metrics of teach-ins against their targets.
  const auto trajectories = reader.trajectories();
  const TrajectoryReferences references(trajectories);
  double error_sum = 0.0;
  Eigen::Index error_points = 0;
  std::vector<double> deviations, procrustes, jerks;
  for (const auto& t : trajectories) {
    if (t.kind == TrajectoryKind::Executed) {
      if (const auto error = references.executionError(t)) {
        error_sum += error->first * static_cast<double>(error->second);
        error_points += error->second;
      }
    } else if (t.kind == TrajectoryKind::TeachIn && t.positions.cols() > 0) {
      const TrajectoryRecord* target = references.targetOf(t);
      if (target && target->positions.cols() > 0) {
        deviations.push_back(maxDeviation(t.positions, target->positions));
        procrustes.push_back(procrustesDistance(t.positions, target->positions).distance);
      }
      try {
        jerks.push_back(jerk(t.times, t.positions).mean);
      } catch (const std::invalid_argument&) {
        // Fewer than four points or repeated times: no jerk for this one.
      }
    }
  }
  if (error_points > 0) result.e_task = error_sum / static_cast<double>(error_points);
  const auto mean = [](const std::vector<double>& v) -> std::optional<double> {
    if (v.empty()) return std::nullopt;
    double sum = 0.0;
    for (const double x : v) sum += x;
    return sum / static_cast<double>(v.size());
  };
  if (!deviations.empty()) result.max_deviation = *std::max_element(deviations.begin(), deviations.end());
  result.procrustes = mean(procrustes);
  result.jerk_mean = mean(jerks);
  result.e_coll_recorded = static_cast<std::int64_t>(reader.collisions().size());
  result.time_per_phase = timePerPhase(reader.stages(), last_time);

  // E_coll (Sect. 3.3) by replay: the recorded postures in the collision world of the recorded
  // robot and scene, an event per pair that starts touching.
  try {
    if (reader.stateCount() == 0) throw InputError("the session holds no robot states (none recorded, or deleted since), so no posture could be replayed");
    const robot::RobotModel model = recordedRobot(reader);
    const robot::Scene scene = meta.scene_text.empty()
                                   ? robot::Scene{}
                                   : robot::parseScene(meta.scene_text, resourceDir() / "scenes",
                                                       "scene recorded in " + result.file, robot::SceneText::kSessionCopy);
    robot::CollisionWorld world(model, scene);
    robot::CollisionMonitor monitor;
    const double interval = std::max(replay_interval, 0.0);
    double next = -1e300;
    // Read in slices so that a long recording does not sit in memory at once.
    constexpr double kSlice = 60.0;  // [s]
    Eigen::VectorXd q(model.dof());
    // Read every stride-th state only: about one per interval at the recorded rate.
    const double duration = reader.endTime() - reader.startTime();
    const double rate = duration > 0.0 ? static_cast<double>(reader.stateCount() - 1) / duration : 1.0;
    const int stride = std::max(1, static_cast<int>(std::floor(interval * rate * (1.0 + 1e-6))));  // 9.999… is 10
    for (double t0 = reader.startTime(); reader.stateCount() > 0 && t0 <= reader.endTime(); t0 += kSlice) {
      const double t1 = std::min(t0 + kSlice, reader.endTime());
      for (const auto& state : reader.states(t0, t1, stride)) {
        if (state.time < next || (t0 > reader.startTime() && state.time <= t0)) continue;
        next = state.time + interval - 0.5 / rate;  // half a sample of slack for rounded times
        if (state.dof != model.dof()) throw InputError("recorded states have " + std::to_string(state.dof) + " joints");
        q = state.qVector();
        world.update(q);
        const auto& contacts = world.contacts();
        monitor.observe(contacts, state.time);
        ++result.replayed_samples;
      }
      if (t1 >= reader.endTime()) break;
    }
    result.e_coll = static_cast<std::int64_t>(monitor.events());
    result.colliding_samples = static_cast<std::int64_t>(monitor.collidingSteps());
  } catch (const InputError& error) {
    result.replay_note = error.what();
  }
  return result;
}

void clusterStudy(StudyResult& study, const StudyOptions& options) {
  study.clusterings.clear();
  study.combinations.clear();
  for (auto& participant : study.participants) participant.cluster.clear();
  // One robot's postures only: the robot most participants used, ties to the first in file order.
  // A robot is known by the URDF the recording stores: the same arm built in ("lwr4"), copied
  // into a cell ("/cell/lwr4.urdf") or the cell moved between participants is one robot, and two
  // arms whose files share a name are two. A recording without the copy (older ones) is known
  // by the robot's name, a URDF file by its name without folder and ".urdf".
  const auto robotKey = [](const ParticipantResult& participant) {
    if (!participant.robot_urdf.empty()) return "urdf:" + participant.robot_urdf;
    const std::filesystem::path file(participant.robot);
    return "name:" + (file.extension() == ".urdf" ? file.stem().string() : participant.robot);
  };
  study.not_clustered.clear();
  std::map<std::string, int> per_robot;
  for (const auto& participant : study.participants) ++per_robot[robotKey(participant)];
  std::string robot;
  std::string robot_key;
  int most = 0;
  for (const auto& participant : study.participants) {
    if (per_robot[robotKey(participant)] > most) {
      most = per_robot[robotKey(participant)];
      robot = participant.robot;
      robot_key = robotKey(participant);
    }
  }
  const auto ofTheStudysRobot = [&](const ParticipantResult& participant) { return robotKey(participant) == robot_key; };
  for (const auto& participant : study.participants) {
    if (!ofTheStudysRobot(participant)) {
      study.not_clustered.push_back(participant.file + ": robot '" + participant.robot + "', the study's postures are of '" + robot + "'");
    }
  }
  study.clustering_note.clear();
  // The robot as a session names it: built in ("lwr4") or a URDF file ("/cell/lwr4.urdf").
  const std::filesystem::path robot_file(robot);
  const bool seeds_fit = robot == options.seeds_robot || (robot_file.extension() == ".urdf" && robot_file.stem().string() == options.seeds_robot);
  if (!options.seeds_robot.empty() && !robot.empty() && !seeds_fit && !options.seeds.empty()) {
    // Another arm's postures near the LWR IV's centres would still fall into "L2" or "R5".
    study.clustering_note = "the initial centres are postures of '" + options.seeds_robot + "' (thesis Tab. B.1), the study's robot is '" +
                            robot + "': give its own with --centres";
    return;
  }
  for (const auto& seeds : options.seeds) {
    if (seeds.centres.empty()) continue;
    const Eigen::Index joints = seeds.centres.front().size();
    AreaClustering clustering;
    clustering.area = seeds.area;
    clustering.names = seeds.names;
    std::vector<std::size_t> members;
    for (std::size_t i = 0; i < study.participants.size(); ++i) {
      const auto found = study.participants[i].q_fixed.find(seeds.area);
      if (ofTheStudysRobot(study.participants[i]) && found != study.participants[i].q_fixed.end() && found->second.size() >= joints) {
        members.push_back(i);
      }
    }
    if (members.empty()) {
      // Centres that fit no session are said, not dropped without a word.
      std::size_t taught = 0;
      Eigen::Index posture_joints = 0;
      for (const auto& participant : study.participants) {
        const auto found = participant.q_fixed.find(seeds.area);
        if (!ofTheStudysRobot(participant) || found == participant.q_fixed.end()) continue;
        ++taught;
        posture_joints = found->second.size();
      }
      study.not_clustered.push_back(
          taught == 0 ? "area " + std::to_string(seeds.area) + ": its centres name an area no session of '" + robot + "' taught"
                      : "area " + std::to_string(seeds.area) + ": its centres hold " + std::to_string(joints) + " joint values, the postures " +
                            std::to_string(posture_joints));
      continue;
    }
    clustering.postures.resize(joints, static_cast<Eigen::Index>(members.size()));
    for (std::size_t m = 0; m < members.size(); ++m) {
      clustering.postures.col(static_cast<Eigen::Index>(m)) =
          study.participants[members[m]].q_fixed.at(seeds.area).head(joints);
      clustering.participants.push_back(study.participants[members[m]].participant);
    }
    Eigen::MatrixXd initial(joints, static_cast<Eigen::Index>(seeds.centres.size()));
    for (std::size_t c = 0; c < seeds.centres.size(); ++c) initial.col(static_cast<Eigen::Index>(c)) = seeds.centres[c];
    clustering.kmeans = kMeans(clustering.postures, initial);
    // MDS of postures and centres together, so that both lie in one plane (Fig. B.2).
    Eigen::MatrixXd all(joints, clustering.postures.cols() + initial.cols());
    all << clustering.postures, clustering.kmeans.centres;
    const Eigen::MatrixXd plane = classicalMds(pairwiseDistances(all), 2);
    clustering.mds = plane.leftCols(clustering.postures.cols());
    clustering.centre_mds = plane.rightCols(initial.cols());
    for (std::size_t m = 0; m < members.size(); ++m) {
      study.participants[members[m]].cluster[seeds.area] =
          seeds.names[static_cast<std::size_t>(clustering.kmeans.labels[m])];
    }
    study.clusterings.push_back(std::move(clustering));
  }

  // Tab. 4.1: participants grouped by their clusters over every clustered area.
  struct Group {
    int users = 0, successful = 0;
    std::vector<double> e_task, e_coll;
  };
  std::map<std::string, Group> groups;
  for (const auto& participant : study.participants) {
    if (participant.cluster.empty() || participant.cluster.size() != study.clusterings.size()) continue;
    std::string name;
    for (const auto& clustering : study.clusterings) {
      name += (name.empty() ? "" : "-") + participant.cluster.at(clustering.area);
    }
    Group& group = groups[name];
    ++group.users;
    if (participant.e_task) group.e_task.push_back(*participant.e_task);
    if (participant.e_coll) group.e_coll.push_back(static_cast<double>(*participant.e_coll));
    const bool accurate = !participant.e_task || *participant.e_task <= options.success_e_task;
    if (accurate && participant.e_coll && *participant.e_coll == 0) ++group.successful;
  }
  for (const auto& [name, group] : groups) {
    study.combinations.push_back(
        {name, group.users, group.successful, median(group.e_task), median(group.e_coll), group.successful > 0});
  }
}

std::vector<std::filesystem::path> studySessionFiles(const std::filesystem::path& folder) {
  if (!std::filesystem::is_directory(folder)) throw InputError("study: '" + folder.string() + "' is no folder");
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    const std::string extension = entry.path().extension().string();
    if (entry.is_regular_file() && (extension == ".flexirob" || extension == ".db" || extension == ".sqlite" ||
                                     extension == ".session")) {
      files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

StudyResult analyseStudy(const std::filesystem::path& folder, const StudyOptions& options) {
  const std::vector<std::filesystem::path> files = studySessionFiles(folder);
  StudyResult study;
  for (std::size_t i = 0; i < files.size(); ++i) {
    if (options.progress) options.progress(files[i].filename().string(), static_cast<double>(i) / static_cast<double>(files.size()));
    try {
      const SessionReader reader(files[i]);
      study.participants.push_back(analyseSession(reader, options.replay_interval));
    } catch (const InputError& error) {
      study.skipped.push_back(files[i].filename().string() + ": " + error.what());
    } catch (const SqliteError& error) {
      // A damaged file among good ones (a row of the wrong size, a corrupt page): skipped, the
      // others analysed.
      study.skipped.push_back(files[i].filename().string() + ": " + error.what());
    } catch (const std::invalid_argument& error) {
      // A damaged trajectory (non-finite points) the metrics refuse: the same.
      study.skipped.push_back(files[i].filename().string() + ": " + error.what());
    }
  }
  if (options.progress) options.progress("clustering", 1.0);
  if (study.participants.empty()) {
    throw InputError("study: no readable session in '" + folder.string() + "' (" + std::to_string(files.size()) +
                     " candidate files; sessions end in .flexirob, .db, .sqlite or .session)");
  }
  clusterStudy(study, options);
  return study;
}

std::vector<std::filesystem::path> writeStudyCsv(const StudyResult& study, const std::filesystem::path& folder,
                                                 const std::vector<OutputFile>& along,
                                                 const std::vector<std::pair<std::string, std::filesystem::path>>& inputs) {
  // All tables or, interrupted or refused, none (writeFilesTogether).
  std::vector<OutputFile> outputs;
  const auto write = [&](const std::string& name, const std::string& text) {
    outputs.push_back({"--csv-dir", folder / name, text});
  };

  std::ostringstream participants;
  participants << "participant,file,robot,scene,closed_cleanly,duration_s,areas,samples,e_task_m,max_deviation_m,"
                  "procrustes_m,jerk_mean_m_s3,e_coll,colliding_samples,replayed_samples,e_coll_recorded";
  for (const auto& clustering : study.clusterings) participants << ",cluster_area" << clustering.area;
  participants << "\n";
  for (const auto& p : study.participants) {
    participants << csvField(p.participant) << ',' << csvField(p.file) << ',' << csvField(p.robot) << ','
                 << csvField(p.scene) << ',' << (p.closed_cleanly ? 1 : 0) << ',' << csvNumber(p.duration_s) << ','
                 << p.areas << ',' << p.samples << ',' << csvNumber(p.e_task) << ',' << csvNumber(p.max_deviation) << ','
                 << csvNumber(p.procrustes) << ',' << csvNumber(p.jerk_mean) << ','
                 << (p.e_coll ? std::to_string(*p.e_coll) : "") << ',' << p.colliding_samples << ','
                 << p.replayed_samples << ',' << p.e_coll_recorded;
    for (const auto& clustering : study.clusterings) {
      const auto found = p.cluster.find(clustering.area);
      participants << ',' << (found == p.cluster.end() ? "" : csvField(found->second));
    }
    participants << "\n";
  }
  write("participants.csv", participants.str());

  std::ostringstream phases;
  phases << "participant,phase,seconds\n";
  for (const auto& p : study.participants) {
    for (const auto& [phase, seconds] : p.time_per_phase) {
      phases << csvField(p.participant) << ',' << csvField(phase) << ',' << csvNumber(seconds) << "\n";
    }
  }
  write("phases.csv", phases.str());

  for (const auto& clustering : study.clusterings) {
    const Eigen::Index joints = clustering.postures.rows();
    std::ostringstream members;
    members << "participant,cluster,mds_x,mds_y";
    for (Eigen::Index j = 0; j < joints; ++j) members << ",q" << j + 1 << "_rad";
    members << "\n";
    for (Eigen::Index m = 0; m < clustering.postures.cols(); ++m) {
      members << csvField(clustering.participants[static_cast<std::size_t>(m)]) << ','
              << csvField(clustering.names[static_cast<std::size_t>(clustering.kmeans.labels[static_cast<std::size_t>(m)])])
              << ',' << csvNumber(clustering.mds(0, m)) << ',' << csvNumber(clustering.mds(1, m));
      for (Eigen::Index j = 0; j < joints; ++j) members << ',' << csvNumber(clustering.postures(j, m));
      members << "\n";
    }
    write("clusters_area" + std::to_string(clustering.area) + ".csv", members.str());

    std::ostringstream centres;
    centres << "cluster,users,mds_x,mds_y";
    for (Eigen::Index j = 0; j < joints; ++j) centres << ",q" << j + 1 << "_rad";
    centres << "\n";
    for (std::size_t c = 0; c < clustering.names.size(); ++c) {
      const auto column = static_cast<Eigen::Index>(c);
      centres << csvField(clustering.names[c]) << ',' << clustering.kmeans.sizes[c] << ','
              << csvNumber(clustering.centre_mds(0, column)) << ',' << csvNumber(clustering.centre_mds(1, column));
      for (Eigen::Index j = 0; j < joints; ++j) centres << ',' << csvNumber(clustering.kmeans.centres(j, column));
      centres << "\n";
    }
    write("centres_area" + std::to_string(clustering.area) + ".csv", centres.str());
  }

  std::ostringstream combinations;
  combinations << "combination,users,successful,median_e_task_m,median_e_coll,consistent\n";
  for (const auto& c : study.combinations) {
    combinations << csvField(c.name) << ',' << c.users << ',' << c.successful << ',' << csvNumber(c.median_e_task)
                 << ',' << csvNumber(c.median_e_coll) << ',' << (c.consistent ? 1 : 0) << "\n";
  }
  write("combinations.csv", combinations.str());
  for (const OutputFile& output : outputs) {
    for (const auto& [option, input] : inputs) {
      if (isExistingFile(output.path, input)) {
        throw InputError("--csv-dir: '" + output.path.string() + "' is the " + option + " file the run reads; give another folder");
      }
    }
  }
  std::error_code error;
  std::filesystem::create_directories(folder, error);
  if (error) throw InputError("--csv-dir: cannot create '" + folder.string() + "': " + error.message());
  std::vector<std::filesystem::path> written;
  for (const OutputFile& output : outputs) written.push_back(output.path);
  outputs.insert(outputs.end(), along.begin(), along.end());
  writeFilesTogether(outputs);
  return written;
}

namespace {

using Rgb = std::array<std::uint8_t, 3>;

// Distinct colours for the first ten clusters drawn in a panel.
constexpr std::array<Rgb, 10> kPalette{{{228, 26, 28},
                                        {55, 126, 184},
                                        {77, 175, 74},
                                        {152, 78, 163},
                                        {255, 127, 0},
                                        {166, 86, 40},
                                        {247, 129, 191},
                                        {0, 0, 0},
                                        {0, 160, 160},
                                        {120, 120, 0}}};

// The colour of the `rank`-th cluster drawn in a panel: the palette's, then hues a golden angle
// apart at two brightnesses, so that a study of many clusters does not draw two alike (the
// palette repeated had coloured the first and the eleventh the same).
Rgb clusterColour(std::size_t rank) {
  if (rank < kPalette.size()) return kPalette[rank];
  const std::size_t n = rank - kPalette.size();
  const double hue = std::fmod(20.0 + 137.50776 * static_cast<double>(n), 360.0) / 60.0;  // sextant
  const double value = n % 2 == 0 ? 0.55 : 0.85;
  const double saturation = 0.9;
  const double chroma = value * saturation;
  const double x = chroma * (1.0 - std::abs(std::fmod(hue, 2.0) - 1.0));
  const std::array<std::array<double, 3>, 6> sextants{{{chroma, x, 0}, {x, chroma, 0}, {0, chroma, x},
                                                        {0, x, chroma}, {x, 0, chroma}, {chroma, 0, x}}};
  const auto& rgb = sextants[static_cast<std::size_t>(hue) % 6];
  const double m = value - chroma;
  const auto channel = [m](double c) { return static_cast<std::uint8_t>(std::lround(255.0 * (c + m))); };
  return {channel(rgb[0]), channel(rgb[1]), channel(rgb[2])};
}

struct Canvas {
  ScatterImage& image;
  void set(int x, int y, const Rgb& colour) const {
    if (x < 0 || y < 0 || x >= image.width || y >= image.height) return;
    const auto i = static_cast<std::size_t>(4 * (y * image.width + x));
    image.rgba[i] = colour[0];
    image.rgba[i + 1] = colour[1];
    image.rgba[i + 2] = colour[2];
    image.rgba[i + 3] = 255;
  }
  void disc(double cx, double cy, double radius, const Rgb& colour) const {
    for (int y = static_cast<int>(cy - radius); y <= static_cast<int>(cy + radius) + 1; ++y) {
      for (int x = static_cast<int>(cx - radius); x <= static_cast<int>(cx + radius) + 1; ++x) {
        if (std::hypot(x - cx, y - cy) <= radius) set(x, y, colour);
      }
    }
  }
  void ring(double cx, double cy, double radius, double width, const Rgb& colour) const {
    for (int y = static_cast<int>(cy - radius - width); y <= static_cast<int>(cy + radius + width) + 1; ++y) {
      for (int x = static_cast<int>(cx - radius - width); x <= static_cast<int>(cx + radius + width) + 1; ++x) {
        if (std::abs(std::hypot(x - cx, y - cy) - radius) <= 0.5 * width) set(x, y, colour);
      }
    }
  }
  void rectangle(int x0, int y0, int x1, int y1, const Rgb& colour) const {
    for (int x = x0; x <= x1; ++x) {
      set(x, y0, colour);
      set(x, y1, colour);
    }
    for (int y = y0; y <= y1; ++y) {
      set(x0, y, colour);
      set(x1, y, colour);
    }
  }
};

}  // namespace

namespace {

// A length of 1, 2 or 5 times a power of ten near `about`, for a scale bar.
double roundLength(double about) {
  const double decade = std::pow(10.0, std::floor(std::log10(about)));
  for (const double step : {5.0, 2.0, 1.0}) {
    if (step * decade <= about) return step * decade;
  }
  return decade;
}

std::string lengthText(double length) {
  std::ostringstream text;
  text << length << " rad";
  return text.str();
}

}  // namespace

ScatterImage renderMdsScatter(const StudyResult& study, int width, int height) {
  if (width < 16 || height < 16 || width > 8192 || height > 8192) {
    throw InputError("scatter plot: expected a size in [16, 8192] pixels");
  }
  ScatterImage image{width, height, std::vector<std::uint8_t>(static_cast<std::size_t>(4 * width * height), 255), {}};
  const Canvas canvas{image};
  const int panels = std::max<int>(1, static_cast<int>(study.clusterings.size()));
  const int panel_width = width / panels;
  constexpr int kMargin = 12;
  constexpr int kTitleBand = 24;    // the panel's title above its frame
  constexpr int kLegendLine = 18;   // one row of the legend
  constexpr int kLegendColumn = 96;  // one entry of a row
  const Rgb frame{160, 160, 160};
  const Rgb ink{40, 40, 40};
  // Each panel's legend: one entry per used cluster and the ring, in columns as wide as the
  // longest entry (about 8 px a character at the legend's 14 px, so that long cluster names are
  // not cut to look alike), then the scale bar on a row of its own. Every frame ends where the
  // tallest legend begins, so that the panels line up.
  struct Legend {
    std::vector<std::size_t> used;  // clusters with members
    int column_width = 0;
    int columns = 1;
    int rows = 0;
  };
  const auto clusterName = [](const AreaClustering& c, std::size_t k) {
    return k < c.names.size() ? c.names[k] : "cluster " + std::to_string(k + 1);
  };
  std::vector<Legend> legends;
  int legend_rows = 0;
  for (const AreaClustering& c : study.clusterings) {
    Legend legend;
    std::size_t longest = std::string("centre").size();
    for (std::size_t k = 0; k < c.kmeans.sizes.size(); ++k) {
      if (c.kmeans.sizes[k] == 0) continue;
      legend.used.push_back(k);
      longest = std::max(longest, clusterName(c, k).size() + 2 + std::to_string(c.kmeans.sizes[k]).size());
    }
    const int inner = std::max(1, panel_width - 2 * kMargin);
    legend.column_width = std::min(inner, std::max(kLegendColumn, 18 + 8 * static_cast<int>(longest)));
    legend.columns = std::max(1, inner / legend.column_width);
    const auto entries = static_cast<int>(legend.used.size()) + 1;
    legend.rows = (entries + legend.columns - 1) / legend.columns + 1;
    legend_rows = std::max(legend_rows, legend.rows);
    legends.push_back(std::move(legend));
  }
  for (int p = 0; p < static_cast<int>(study.clusterings.size()); ++p) {
    const AreaClustering& c = study.clusterings[static_cast<std::size_t>(p)];
    const int x0 = p * panel_width + kMargin;
    const int x1 = (p + 1) * panel_width - kMargin;
    const Legend& legend = legends[static_cast<std::size_t>(p)];
    const std::vector<std::size_t>& used = legend.used;
    // Colours by the order the legend lists the clusters in, the members' and the centre's alike.
    std::vector<Rgb> colour(c.kmeans.sizes.size(), ink);
    for (std::size_t e = 0; e < used.size(); ++e) colour[used[e]] = clusterColour(e);
    const int column_width = legend.column_width;
    const int columns = legend.columns;
    const int y0 = kMargin + kTitleBand;
    const int y1 = height - kMargin - legend_rows * kLegendLine;
    if (y1 - y0 < 16 || x1 - x0 < 16) continue;  // too small a picture for this panel's plot
    std::ostringstream title;
    title << "Area " << c.area << ": " << c.participants.size() << (c.participants.size() == 1 ? " participant, " : " participants, ")
          << used.size() << (used.size() == 1 ? " cluster" : " clusters");
    image.labels.push_back({title.str(), x0 - 4, kMargin + kTitleBand - 9, x1 - x0 + 8});
    canvas.rectangle(x0 - 4, y0 - 4, x1 + 4, y1 + 4, frame);
    // One scale for both axes (MDS distances are meaningful), fitted to what is drawn: the
    // postures and the used centres (an unused seed far off would leave them in one corner).
    Eigen::MatrixXd all(2, c.mds.cols() + static_cast<Eigen::Index>(used.size()));
    all.leftCols(c.mds.cols()) = c.mds;
    for (std::size_t u = 0; u < used.size(); ++u) {
      all.col(c.mds.cols() + static_cast<Eigen::Index>(u)) = c.centre_mds.col(static_cast<Eigen::Index>(used[u]));
    }
    const Eigen::Vector2d low = all.rowwise().minCoeff();
    const Eigen::Vector2d high = all.rowwise().maxCoeff();
    // A single posture, or postures all alike, span nothing: a tenth of a radian is drawn as the
    // plot's width then, so that the scale bar still says a true length.
    const double span = std::max({high.x() - low.x(), high.y() - low.y(), 0.1});
    constexpr int kRingRoom = 8;  // a centre's ring stays inside the frame
    const double scale = std::max(1, std::min(x1 - x0, y1 - y0) - 2 * kRingRoom) / span;
    const double ox = 0.5 * (x0 + x1) - scale * 0.5 * (low.x() + high.x());
    const double oy = 0.5 * (y0 + y1) + scale * 0.5 * (low.y() + high.y());
    const auto px = [&](double x) { return ox + scale * x; };
    const auto py = [&](double y) { return oy - scale * y; };  // y up
    for (Eigen::Index m = 0; m < c.mds.cols(); ++m) {
      const auto label = static_cast<std::size_t>(c.kmeans.labels[static_cast<std::size_t>(m)]);
      canvas.disc(px(c.mds(0, m)), py(c.mds(1, m)), 4.0, colour.at(label));
    }
    for (const std::size_t k : used) {
      canvas.ring(px(c.centre_mds(0, static_cast<Eigen::Index>(k))), py(c.centre_mds(1, static_cast<Eigen::Index>(k))), 9.0, 2.0,
                  colour[k]);
    }
    const auto entry_at = [&](int index) {
      return std::pair<int, int>{x0 + (index % columns) * column_width, y1 + 4 + (index / columns + 1) * kLegendLine};
    };
    for (std::size_t e = 0; e < used.size(); ++e) {
      const std::size_t k = used[e];
      const auto [x, baseline] = entry_at(static_cast<int>(e));
      canvas.disc(x + 5, baseline - 5, 4.0, colour[k]);
      const std::string name = clusterName(c, k);
      image.labels.push_back({name + ": " + std::to_string(c.kmeans.sizes[k]), x + 14, baseline, column_width - 18});
    }
    {
      const auto [x, baseline] = entry_at(static_cast<int>(used.size()));
      canvas.ring(x + 5, baseline - 5, 4.5, 1.5, ink);
      image.labels.push_back({"centre", x + 14, baseline, column_width - 18});
    }
    // The scale bar: MDS keeps the distances between postures (Euclidean, in joint space).
    const double bar = roundLength(0.3 * (x1 - x0) / scale);
    const int bar_pixels = std::max(1, static_cast<int>(std::lround(bar * scale)));
    const int bar_baseline = y1 + 4 + legend_rows * kLegendLine;
    for (int dy = -6; dy <= -4; ++dy) {
      for (int x = x0; x <= x0 + bar_pixels; ++x) canvas.set(x, bar_baseline + dy, ink);
    }
    for (int dy = -9; dy <= -1; ++dy) {
      canvas.set(x0, bar_baseline + dy, ink);
      canvas.set(x0 + bar_pixels, bar_baseline + dy, ink);
    }
    image.labels.push_back({lengthText(bar) + " (joint space)", x0 + bar_pixels + 8, bar_baseline, x1 - x0 - bar_pixels - 8});
  }
  return image;
}

}  // namespace flexirob::app
