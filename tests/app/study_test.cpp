// Study analysis: k-means from given centres, classical MDS, the Tab. B.1 seeds, the table of
// consistent combinations, CSV export and E_coll by replaying a recording against its scene.
#include "app/study.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <set>
#include <sstream>
#include <unistd.h>

#include "app/session_reader.hpp"
#include "app/session_recorder.hpp"
#include "app/session_schema.hpp"
#include "robot/backend.hpp"
#include "robot/errors.hpp"
#include "robot/kinematics.hpp"
#include "robot/resources.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

namespace flexirob::app {
namespace {

std::filesystem::path scratchDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("flexirob-study-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::string readFile(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream stream(text);
  std::string line;
  while (std::getline(stream, line)) out.push_back(line);
  return out;
}

TEST(KMeans, FindsWellSeparatedClustersFromGivenCentres) {
  // Three clusters in 6-D; each point is its cluster's mean plus ± offsets that cancel, so the
  // exact means are known.
  Eigen::MatrixXd means(6, 3);
  means.col(0) << 0, 1.5, -1.5, -1.5, 1.5, 1.5;
  means.col(1) << 0, 1.5, -1.5, -1.5, -1.5, -1.5;
  means.col(2) << 0, 1.5, 1.5, 1.5, -1.5, 1.5;
  const std::vector<int> truth{0, 0, 1, 2, 2, 1, 0, 2, 0, 1, 2, 1};
  Eigen::MatrixXd points(6, static_cast<Eigen::Index>(truth.size()));
  std::vector<int> seen(3, 0);
  for (std::size_t p = 0; p < truth.size(); ++p) {
    const int c = truth[p];
    const double sign = (seen[static_cast<std::size_t>(c)]++ % 2 == 0) ? 1.0 : -1.0;
    Eigen::VectorXd offset(6);
    offset << 0.1, -0.05, 0.08, 0.02, -0.1, 0.04;
    points.col(static_cast<Eigen::Index>(p)) = means.col(c) + sign * offset;
  }
  // Every cluster has an even count, so the offsets cancel.
  for (const int count : seen) ASSERT_EQ(count % 2, 0);
  Eigen::MatrixXd initial = means;
  initial.array() += 0.3;  // seeds near, not at, the clusters (as Tab. B.1's prototypes)
  const KMeansResult result = kMeans(points, initial);
  EXPECT_TRUE(result.converged);
  EXPECT_EQ(result.labels, truth);
  EXPECT_LT((result.centres - means).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(result.sizes, (std::vector<int>{4, 4, 4}));
  const double offset_norm2 = (Eigen::VectorXd(6) << 0.1, -0.05, 0.08, 0.02, -0.1, 0.04).finished().squaredNorm();
  EXPECT_NEAR(result.inertia, 12 * offset_norm2, 1e-12);
}

TEST(KMeans, KeepsASeedWithoutPointsAndBreaksTiesTowardsTheLowerIndex) {
  Eigen::MatrixXd points(1, 4);
  points << -1.0, -1.2, 1.0, 1.2;
  Eigen::MatrixXd initial(1, 3);
  initial << -1.0, 1.0, 50.0;
  const KMeansResult result = kMeans(points, initial);
  EXPECT_EQ(result.sizes, (std::vector<int>{2, 2, 0}));
  EXPECT_DOUBLE_EQ(result.centres(0, 2), 50.0);
  EXPECT_DOUBLE_EQ(result.centres(0, 0), -1.1);
  // A point half-way between two seeds goes to the first.
  Eigen::MatrixXd middle(1, 1);
  middle << 0.0;
  Eigen::MatrixXd two(1, 2);
  two << -1.0, 1.0;
  EXPECT_EQ(kMeans(middle, two).labels, std::vector<int>{0});
  EXPECT_THROW(kMeans(Eigen::MatrixXd(2, 3), Eigen::MatrixXd(3, 2)), std::invalid_argument);
  EXPECT_THROW(kMeans(Eigen::MatrixXd(2, 0), Eigen::MatrixXd::Zero(2, 2)), std::invalid_argument);
}

TEST(ClassicalMds, ReproducesTheDistancesOfPlanarPoints) {
  // Points on a plane embedded in 6-D (rotated and shifted): the 2-D MDS keeps every distance.
  std::mt19937 random(3);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXd planar(2, 9);
  for (Eigen::Index i = 0; i < planar.size(); ++i) planar(i) = normal(random);
  Eigen::MatrixXd basis(6, 6);
  for (Eigen::Index i = 0; i < basis.size(); ++i) basis(i) = normal(random);
  const Eigen::MatrixXd Q = basis.householderQr().householderQ();
  Eigen::VectorXd shift(6);
  shift << 1, -2, 3, 0.5, 0, 7;
  const Eigen::MatrixXd embedded = (Q.leftCols(2) * planar).colwise() + shift;
  const Eigen::MatrixXd D = pairwiseDistances(embedded);
  const Eigen::MatrixXd coordinates = classicalMds(D, 2);
  ASSERT_EQ(coordinates.rows(), 2);
  ASSERT_EQ(coordinates.cols(), 9);
  EXPECT_LT((pairwiseDistances(coordinates) - D).cwiseAbs().maxCoeff(), 1e-9);
  // Centred at the origin.
  EXPECT_LT(coordinates.rowwise().mean().norm(), 1e-9);
}

TEST(ClassicalMds, PlacesAnEquilateralTriangleAndAUnitSquare) {
  Eigen::MatrixXd triangle = Eigen::MatrixXd::Ones(3, 3) - Eigen::MatrixXd::Identity(3, 3);
  const Eigen::MatrixXd t = classicalMds(triangle, 2);
  EXPECT_LT((pairwiseDistances(t) - triangle).cwiseAbs().maxCoeff(), 1e-9);
  // Distance from the centroid: 1/sqrt(3).
  for (Eigen::Index i = 0; i < 3; ++i) EXPECT_NEAR(t.col(i).norm(), 1.0 / std::sqrt(3.0), 1e-9);
  const double s = std::sqrt(2.0);
  Eigen::MatrixXd square(4, 4);
  square << 0, 1, s, 1, 1, 0, 1, s, s, 1, 0, 1, 1, s, 1, 0;
  EXPECT_LT((pairwiseDistances(classicalMds(square, 2)) - square).cwiseAbs().maxCoeff(), 1e-9);
  Eigen::MatrixXd asymmetric = square;
  asymmetric(0, 1) = 3.0;
  EXPECT_THROW(classicalMds(asymmetric, 2), std::invalid_argument);
}

TEST(StudyClusters, SeedsAreThoseOfTableB1) {
  const auto seeds = thesisClusterSeeds();
  ASSERT_EQ(seeds.size(), 2U);
  EXPECT_EQ(seeds[0].names, (std::vector<std::string>{"L1", "L2", "L3"}));
  EXPECT_EQ(seeds[1].names.size(), 7U);
  const double h = std::numbers::pi / 2.0;
  Eigen::VectorXd l3(6);
  l3 << 0, h, h, h, -h, h;
  EXPECT_EQ(seeds[0].centres[2], l3);
  Eigen::VectorXd r7(6);
  r7 << std::numbers::pi / 4.0, h, std::numbers::pi / 4.0, 0, -std::numbers::pi / 4.0, h;
  EXPECT_EQ(seeds[1].centres[6], r7);
}

TEST(StudyClusters, ReadsSeedFilesAndRefusesBadOnes) {
  const auto dir = scratchDir("seeds");
  {
    std::ofstream out(dir / "seeds.csv");
    out << "area,name,q1,q2\n0,A,0.0,1.0\n0,B,1.0,0.0\n\n# right\n2,C,0.5,0.5\n";
  }
  const auto seeds = loadClusterSeeds(dir / "seeds.csv");
  ASSERT_EQ(seeds.size(), 2U);
  EXPECT_EQ(seeds[0].area, 0);
  EXPECT_EQ(seeds[0].names, (std::vector<std::string>{"A", "B"}));
  EXPECT_EQ(seeds[1].area, 2);
  EXPECT_DOUBLE_EQ(seeds[1].centres[0][1], 0.5);
  const auto refused = [&dir](const std::string& text) {
    {
      std::ofstream out(dir / "bad.csv");
      out << text;
    }
    EXPECT_THROW(loadClusterSeeds(dir / "bad.csv"), InputError) << text;
  };
  refused("");
  refused("x,A,1,2\n");
  refused("0,A,1,zwei\n");
  refused("0,A,1,2\n0,B,1\n");
  refused("0,,1,2\n");
  refused("0,A,nan,2\n");
  refused("0,A,1e300,2\n");
  refused("0,A,0x1,2\n");                    // decimal only, as every other table
  refused("area,name,q1\r0,A,1\r1,B,2\r");  // carriage returns alone as line ends
  // A spreadsheet's byte order mark before the header is read past.
  {
    std::ofstream out(dir / "marked.csv");
    out << "\xEF\xBB\xBF" << "area,name,q1,q2\n0,A,0.0,1.0\n";
  }
  EXPECT_EQ(loadClusterSeeds(dir / "marked.csv").size(), 1U);
  // Comments and blank lines may come before the header; a header later is no row.
  {
    std::ofstream out(dir / "commented.csv");
    out << "# seeds of Tab. B.1\n\narea,name,q1,q2\n0,A,0.0,1.0\n";
  }
  EXPECT_EQ(loadClusterSeeds(dir / "commented.csv").size(), 1U);
  refused("0,A,0.0,1.0\narea,name,q1,q2\n");
  EXPECT_THROW(loadClusterSeeds(dir / "missing.csv"), InputError);
  std::filesystem::remove_all(dir);
}

ParticipantResult participant(const std::string& name, const Eigen::VectorXd& left, const Eigen::VectorXd& right,
                              std::optional<double> e_task, std::int64_t e_coll) {
  ParticipantResult p;
  p.participant = name;
  p.file = name + ".db";
  p.robot = "lwr4";
  p.q_fixed[0] = left;
  p.q_fixed[1] = right;
  p.e_task = e_task;
  p.e_coll = e_coll;
  return p;
}

// Postures near a Tab. B.1 seed (7 joints: q7 is not clustered).
Eigen::VectorXd near(const Eigen::VectorXd& seed, double offset) {
  Eigen::VectorXd q(7);
  q << seed.array() + offset, 2.5;
  return q;
}

// Four participants near Tab. B.1's centres: the first, second and fourth in L1-R6, the third
// in L3-R1.
std::vector<ParticipantResult> fourParticipants(const std::array<std::string, 4>& names) {
  const auto seeds = thesisClusterSeeds();
  const auto& L = seeds[0].centres;
  const auto& R = seeds[1].centres;
  return {participant(names[0], near(L[0], 0.05), near(R[5], -0.04), 0.004, 0),
          participant(names[1], near(L[0], -0.1), near(R[5], 0.02), 0.006, 0),
          participant(names[2], near(L[2], 0.0), near(R[0], 0.0), 0.004, 0),
          participant(names[3], near(L[0], 0.0), near(R[5], 0.0), 0.009, 0)};
}

TEST(StudyClusters, TabulatesConsistentCombinations) {
  const auto seeds = thesisClusterSeeds();
  const auto& L = seeds[0].centres;
  const auto& R = seeds[1].centres;
  StudyResult study;
  study.participants = {participant("p1", near(L[0], 0.05), near(R[5], -0.04), 0.004, 0),  // L1-R6 success
                        participant("p2", near(L[0], -0.1), near(R[5], 0.02), 0.03, 0),   // L1-R6 inaccurate
                        participant("p3", near(L[2], 0.02), near(R[3], 0.1), 0.008, 2),   // L3-R4 collided
                        participant("p4", near(L[2], -0.07), near(R[0], 0.0), 0.05, 4),   // L3-R1
                        participant("p5", near(L[0], 0.0), near(R[5], 0.0), 0.009, 0)};   // L1-R6 success
  StudyOptions options;
  clusterStudy(study, options);
  ASSERT_EQ(study.clusterings.size(), 2U);
  EXPECT_EQ(study.participants[0].cluster.at(0), "L1");
  EXPECT_EQ(study.participants[0].cluster.at(1), "R6");
  EXPECT_EQ(study.participants[2].cluster.at(0), "L3");
  EXPECT_EQ(study.participants[3].cluster.at(1), "R1");
  EXPECT_EQ(study.clusterings[0].kmeans.sizes, (std::vector<int>{3, 0, 2}));
  // The left area's centres are the means of their members' first six joints.
  const Eigen::VectorXd l1_mean = (near(L[0], 0.05) + near(L[0], -0.1) + near(L[0], 0.0)).head(6) / 3.0;
  EXPECT_LT((study.clusterings[0].kmeans.centres.col(0) - l1_mean).norm(), 1e-12);
  EXPECT_EQ(study.clusterings[0].mds.cols(), 5);
  EXPECT_EQ(study.clusterings[0].centre_mds.cols(), 3);

  ASSERT_EQ(study.combinations.size(), 3U);
  const auto find = [&study](const std::string& name) {
    for (const auto& c : study.combinations) {
      if (c.name == name) return c;
    }
    ADD_FAILURE() << name;
    return Combination{};
  };
  const Combination l1r6 = find("L1-R6");
  EXPECT_EQ(l1r6.users, 3);
  EXPECT_EQ(l1r6.successful, 2);
  EXPECT_TRUE(l1r6.consistent);
  EXPECT_NEAR(*l1r6.median_e_task, 0.009, 1e-12);
  EXPECT_NEAR(*l1r6.median_e_coll, 0.0, 1e-12);
  const Combination l3r4 = find("L3-R4");
  EXPECT_EQ(l3r4.users, 1);
  EXPECT_FALSE(l3r4.consistent);
  EXPECT_FALSE(find("L3-R1").consistent);

  // CSV: every table, with a header and one row per entry.
  const auto dir = scratchDir("csv");
  const auto files = writeStudyCsv(study, dir);
  EXPECT_EQ(files.size(), 7U);  // participants, phases, clusters and centres of two areas, combinations
  const auto participants = lines(readFile(dir / "participants.csv"));
  ASSERT_EQ(participants.size(), 6U);
  EXPECT_EQ(participants[0].rfind("participant,file,robot,scene,closed_cleanly,duration_s", 0), 0U);
  EXPECT_NE(participants[0].find(",cluster_area0,cluster_area1"), std::string::npos);
  EXPECT_NE(participants[1].find(",L1,R6"), std::string::npos);
  const auto combinations = lines(readFile(dir / "combinations.csv"));
  ASSERT_EQ(combinations.size(), 4U);
  EXPECT_EQ(combinations[0], "combination,users,successful,median_e_task_m,median_e_coll,consistent");
  EXPECT_EQ(combinations[1], "L1-R6,3,2,0.009,0,1");
  const auto centres = lines(readFile(dir / "centres_area1.csv"));
  EXPECT_EQ(centres.size(), 8U);  // header + R1..R7
  EXPECT_EQ(lines(readFile(dir / "clusters_area0.csv")).size(), 6U);

  // The scatter plot: points coloured by cluster, the rest white.
  const ScatterImage image = renderMdsScatter(study, 400, 200);
  ASSERT_EQ(image.rgba.size(), 400U * 200U * 4U);
  int coloured = 0;
  for (std::size_t i = 0; i < image.rgba.size(); i += 4) {
    coloured += image.rgba[i] != image.rgba[i + 1] || image.rgba[i + 1] != image.rgba[i + 2] ? 1 : 0;
  }
  EXPECT_GT(coloured, 5 * 20);  // at least the discs of the members of one panel
  // Each panel says what it shows: the area and its participants, each used cluster's name and
  // members (L2 has none), and the length of its scale bar.
  const auto labelled = [&image](const std::string& text) {
    return std::count_if(image.labels.begin(), image.labels.end(), [&text](const ScatterLabel& label) { return label.text == text; });
  };
  EXPECT_EQ(labelled("Area 0: 5 participants, 2 clusters"), 1);
  EXPECT_EQ(labelled("L1: 3"), 1);
  EXPECT_EQ(labelled("L3: 2"), 1);
  EXPECT_EQ(labelled("L2: 0"), 0);
  EXPECT_EQ(labelled("centre"), 2);
  const auto bars = std::count_if(image.labels.begin(), image.labels.end(), [](const ScatterLabel& label) {
    return label.text.find(" rad (joint space)") != std::string::npos;
  });
  EXPECT_EQ(bars, 2);
  for (const ScatterLabel& label : image.labels) {
    EXPECT_GE(label.x, 0) << label.text;
    EXPECT_LE(label.x + label.max_width, image.width) << label.text;
    EXPECT_GT(label.baseline, 0) << label.text;
    EXPECT_LE(label.baseline, image.height) << label.text;
  }
  std::filesystem::remove_all(dir);
}

// A study of many clusters draws each in a colour of its own: the legend's disc beside each
// cluster's entry differs from every other's.
TEST(StudyPlot, TwelveClustersAreDrawnInTwelveColours) {
  StudyOptions options;
  AreaClusterSeeds many;
  many.area = 0;
  StudyResult study;
  const auto right = thesisClusterSeeds()[1].centres[0];
  for (int k = 0; k < 12; ++k) {
    Eigen::VectorXd centre = Eigen::VectorXd::Zero(6);
    centre(0) = -1.5 + 0.25 * k;
    centre(1) = k % 2 == 0 ? 0.3 : -0.3;
    many.names.push_back("C" + std::to_string(k + 1));
    many.centres.push_back(centre);
    study.participants.push_back(participant("p" + std::to_string(k + 1), near(centre, 0.01), near(right, 0.0), 0.004, 0));
  }
  options.seeds = {many, thesisClusterSeeds()[1]};
  clusterStudy(study, options);
  ASSERT_EQ(study.clusterings.size(), 2U);
  ASSERT_EQ(study.clusterings[0].kmeans.sizes, std::vector<int>(12, 1));
  const ScatterImage image = renderMdsScatter(study, 1200, 600);
  std::set<std::array<std::uint8_t, 3>> colours;
  int entries = 0;
  for (const ScatterLabel& label : image.labels) {
    if (label.text.size() < 4 || label.text[0] != 'C' || label.text.substr(label.text.size() - 3) != ": 1") continue;
    ++entries;
    // The disc sits 9 px left of the entry's text, 5 px above its baseline (renderMdsScatter).
    const std::size_t i = (static_cast<std::size_t>(label.baseline - 5) * static_cast<std::size_t>(image.width) +
                           static_cast<std::size_t>(label.x - 9)) * 4;
    ASSERT_LT(i + 2, image.rgba.size());
    colours.insert({image.rgba[i], image.rgba[i + 1], image.rgba[i + 2]});
  }
  EXPECT_EQ(entries, 12);
  EXPECT_EQ(colours.size(), 12U);
  EXPECT_EQ(colours.count({255, 255, 255}), 0U) << "a disc is drawn under every entry";
}

const robot::RobotModel& lwr4() {
  static const robot::RobotModel model = robot::RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  return model;
}

// Records `postures` (each held for `hold` states at 1 kHz) into a session with `scene`.
void recordPostures(const std::filesystem::path& file, const robot::Scene& scene,
                    const std::vector<Eigen::VectorXd>& postures, int hold) {
  SessionMetadata metadata;
  metadata.robot_name = "lwr4";
  metadata.tip_link = lwr4().tipLink();
  metadata.scene_name = scene.name;
  metadata.scene_text = robot::sceneToYaml(scene);
  metadata.participant = file.stem().string();
  SessionRecorder recorder(file, metadata);
  robot::RobotState state;
  state.resize(7);
  double time = 0.0;
  for (const auto& q : postures) {
    for (int i = 0; i < hold; ++i) {
      state.time = time;
      state.q = q;
      state.q_cmd = q;
      state.X_WT = robot::tipPose(lwr4(), q);
      while (!recorder.recordState(state)) {
      }
      time += 1e-3;
    }
  }
  recorder.recordArea({0, 0.0, robot::tipPose(lwr4(), postures.front()).translation(), postures.front(), "front"});
  recorder.close();
}

// Postures of another robot are not comparable: a study folder holding one arm9 session among
// LWR IV sessions clusters the LWR IV's and names the other, whatever its postures.
TEST(StudyClusters, ClustersTheRobotMostParticipantsUsedAndNamesTheOthers) {
  StudyResult study;
  study.participants = fourParticipants({"p1", "p2", "other", "p3"});
  for (auto& p : study.participants) p.robot = "lwr4";
  study.participants[2].robot = "arm9";
  StudyOptions options;
  clusterStudy(study, options);
  ASSERT_EQ(study.clusterings.size(), 2U);
  EXPECT_EQ(study.clusterings[0].participants, (std::vector<std::string>{"p1", "p2", "p3"}));
  EXPECT_EQ(study.clusterings[0].kmeans.sizes, (std::vector<int>{3, 0, 0}));
  EXPECT_TRUE(study.participants[2].cluster.empty());
  ASSERT_EQ(study.not_clustered.size(), 1U);
  EXPECT_EQ(study.not_clustered[0], "other.db: robot 'arm9', the study's postures are of 'lwr4'");
  EXPECT_TRUE(study.clustering_note.empty());
  // Two against two: the robot of the first file. Tab. B.1's centres are the LWR IV's: arm9's
  // postures are not clustered against them, and the study says why.
  study.participants[0].robot = "arm9";
  clusterStudy(study, options);
  ASSERT_EQ(study.not_clustered.size(), 2U);
  EXPECT_EQ(study.not_clustered[0], "p2.db: robot 'lwr4', the study's postures are of 'arm9'");
  EXPECT_EQ(study.not_clustered[1], "p3.db: robot 'lwr4', the study's postures are of 'arm9'");
  EXPECT_TRUE(study.clusterings.empty());
  EXPECT_TRUE(study.participants[0].cluster.empty());
  EXPECT_NE(study.clustering_note.find("postures of 'lwr4' (thesis Tab. B.1), the study's robot is 'arm9'"), std::string::npos)
      << study.clustering_note;
  // The LWR IV's URDF given as a file is the LWR IV.
  for (auto& p : study.participants) p.robot = "/cell/robots/lwr4.urdf";
  clusterStudy(study, options);
  EXPECT_TRUE(study.clustering_note.empty()) << study.clustering_note;
  EXPECT_EQ(study.clusterings.size(), 2U);
  for (auto& p : study.participants) p.robot = "lwr4";
  study.participants[0].robot = "arm9";
  study.participants[2].robot = "arm9";
  // Centres given for the study's own robot (--centres) cluster it.
  options.seeds_robot.clear();
  clusterStudy(study, options);
  EXPECT_TRUE(study.clustering_note.empty());
  ASSERT_EQ(study.clusterings.size(), 2U);
  EXPECT_EQ(study.clusterings[0].participants, (std::vector<std::string>{"p1", "other"}));
}

// One arm under several names: built in, as a copy in a cell's folder, and the cell moved to
// another folder between participants; the URDF each recording stores is the same, so their
// postures are one robot's. Another arm whose file has the same name is another robot, and
// recordings without the stored URDF are told apart by the file's name.
TEST(StudyClusters, TheSameArmByNameOrByItsUrdfFileInAnyFolderIsOneRobot) {
  StudyResult study;
  study.participants = fourParticipants({"p1", "p2", "p3", "p4"});
  const std::string lwr4_urdf = "<robot name=\"lwr4\">...</robot>";
  study.participants[0].robot = "lwr4";
  study.participants[1].robot = "/old/cell/lwr4.urdf";
  study.participants[2].robot = "/new/cell/lwr4.urdf";
  study.participants[3].robot = "/other/cell/lwr4.urdf";
  for (int i = 0; i < 3; ++i) study.participants[static_cast<std::size_t>(i)].robot_urdf = lwr4_urdf;
  study.participants[3].robot_urdf = "<robot name=\"another_arm\">...</robot>";
  clusterStudy(study, StudyOptions{});
  ASSERT_EQ(study.clusterings.size(), 2U);
  EXPECT_EQ(study.clusterings[0].participants, (std::vector<std::string>{"p1", "p2", "p3"}));
  ASSERT_EQ(study.not_clustered.size(), 1U);
  EXPECT_EQ(study.not_clustered[0].rfind("p4.db: robot '/other/cell/lwr4.urdf'", 0), 0U) << study.not_clustered[0];
  EXPECT_TRUE(study.clustering_note.empty()) << study.clustering_note;

  // Without stored URDFs: the file's name decides.
  for (auto& p : study.participants) p.robot_urdf.clear();
  study.participants[3].robot = "/new/cell/other_arm.urdf";
  clusterStudy(study, StudyOptions{});
  EXPECT_EQ(study.clusterings.at(0).participants, (std::vector<std::string>{"p1", "p2", "p3"}));
  ASSERT_EQ(study.not_clustered.size(), 1U);
  EXPECT_EQ(study.not_clustered[0].rfind("p4.db: robot '/new/cell/other_arm.urdf'", 0), 0U) << study.not_clustered[0];
}

// Centres of an area no session taught, or of more joints than the postures hold (given with
// --centres for another arm): nothing to cluster, and the study says why for each area.
TEST(StudyClusters, SaysWhichGivenCentresFitNoSession) {
  const auto seeds = thesisClusterSeeds();
  StudyResult study;
  study.participants = {participant("p1", near(seeds[0].centres[0], 0.05), near(seeds[1].centres[5], -0.04), 0.004, 0),
                        participant("p2", near(seeds[0].centres[0], -0.1), near(seeds[1].centres[5], 0.02), 0.006, 0)};
  for (auto& p : study.participants) p.robot = "lwr4";
  StudyOptions options;
  options.seeds_robot.clear();
  AreaClusterSeeds too_long;
  too_long.area = 0;
  too_long.names = {"A", "B"};
  too_long.centres = {Eigen::VectorXd::Zero(9), Eigen::VectorXd::Ones(9)};
  AreaClusterSeeds untaught = too_long;
  untaught.area = 5;
  untaught.centres = {Eigen::VectorXd::Zero(3), Eigen::VectorXd::Ones(3)};
  options.seeds = {too_long, untaught};
  clusterStudy(study, options);
  EXPECT_TRUE(study.clusterings.empty());
  ASSERT_EQ(study.not_clustered.size(), 2U);
  EXPECT_EQ(study.not_clustered[0], "area 0: its centres hold 9 joint values, the postures 7");
  EXPECT_EQ(study.not_clustered[1], "area 5: its centres name an area no session of 'lwr4' taught");
}

// A session whose state rows were deleted (or never recorded) still has its stages and areas:
// its duration is theirs, not 0, and E_coll is unknown, not 0.
TEST(StudyReplay, ASessionWithoutStatesLastsAsLongAsItsEventsAndReplaysNothing) {
  const auto dir = scratchDir("no-states");
  Eigen::VectorXd q(7);
  q << 0.0, 0.6, 0.0, -1.6, 0.0, 0.9, 0.0;
  robot::Scene empty;
  empty.name = "empty";
  {
    SessionMetadata metadata;
    metadata.robot_name = "lwr4";
    metadata.tip_link = lwr4().tipLink();
    metadata.scene_name = empty.name;
    metadata.scene_text = robot::sceneToYaml(empty);
    SessionRecorder recorder(dir / "cut.db", metadata);
    robot::RobotState state;
    state.resize(7);
    state.q = q;
    state.q_cmd = q;
    state.X_WT = robot::tipPose(lwr4(), q);
    for (int i = 0; i <= 4000; ++i) {  // 0 .. 4 s
      state.time = 1e-3 * i;
      while (!recorder.recordState(state)) {
      }
    }
    recorder.recordStage({0.5, "CONFIGURATION", "APPROACHING"});
    recorder.recordStage({1.25, "CONFIGURATION", "RECORDING"});
    recorder.recordArea({0, 1.25, state.X_WT.translation(), q, "front"});
    recorder.recordStage({3.75, "PROGRAMMING", "APPROACHING"});
    recorder.close();
  }
  // With its states, the span is theirs.
  EXPECT_EQ(SessionReader(dir / "cut.db").recordedTimeSpan(), (std::pair<double, double>{0.0, 4.0}));
  {
    SqliteDatabase db((dir / "cut.db").string(), 0x00000002);  // SQLITE_OPEN_READWRITE
    db.exec("DELETE FROM state");
  }
  const SessionReader reader(dir / "cut.db");
  EXPECT_EQ(reader.stateCount(), 0);
  EXPECT_EQ(reader.recordedTimeSpan(), (std::pair<double, double>{0.5, 3.75}));
  const ParticipantResult result = analyseSession(reader, 0.0);
  EXPECT_DOUBLE_EQ(result.duration_s, 3.25);
  EXPECT_FALSE(result.e_coll.has_value());
  EXPECT_NE(result.replay_note.find("no robot states"), std::string::npos) << result.replay_note;
  EXPECT_EQ(result.replayed_samples, 0);
  EXPECT_EQ(result.areas, 1);
  std::filesystem::remove_all(dir);
}

TEST(StudyReplay, CountsContactsOfTheRecordedPosturesInTheRecordedScene) {
  const auto dir = scratchDir("replay");
  Eigen::VectorXd free_q(7), touching_q(7);
  free_q << 0.0, 0.6, 0.0, -1.6, 0.0, 0.9, 0.0;
  touching_q = free_q;
  touching_q[1] = 0.9;  // the tip moves forward and down
  // A small box around the tip at touching_q, away from where the tip is at free_q.
  const Eigen::Vector3d p_touch = robot::tipPose(lwr4(), touching_q).translation();
  const Eigen::Vector3d p_free = robot::tipPose(lwr4(), free_q).translation();
  ASSERT_GT((p_touch - p_free).norm(), 0.15);
  robot::Scene scene;
  scene.name = "replay_box";
  robot::Obstacle box;
  box.name = "box";
  box.shape = robot::Obstacle::Shape::kBox;
  box.X_WO.translation() = p_touch;
  box.size = Eigen::Vector3d::Constant(0.04);
  scene.obstacles.push_back(box);

  // free, touch, free, touch, free: two entries into contact, 200 colliding states of 500.
  recordPostures(dir / "box.db", scene, {free_q, touching_q, free_q, touching_q, free_q}, 100);
  const ParticipantResult hit = analyseSession(SessionReader(dir / "box.db"), 0.0);
  ASSERT_TRUE(hit.e_coll.has_value()) << hit.replay_note;
  EXPECT_EQ(hit.replayed_samples, 500);
  EXPECT_EQ(hit.colliding_samples, 200);
  EXPECT_GE(*hit.e_coll, 2);
  EXPECT_EQ(*hit.e_coll % 2, 0);  // the same pairs start touching at both entries
  EXPECT_EQ(hit.participant, "box");
  EXPECT_EQ(hit.areas, 1);

  // Every 10 ms: the same events, a tenth of the samples.
  const ParticipantResult sparse = analyseSession(SessionReader(dir / "box.db"), 0.01);
  EXPECT_EQ(sparse.e_coll, hit.e_coll);
  EXPECT_NEAR(static_cast<double>(sparse.replayed_samples), 50.0, 1.0);

  // The same motion without the box: nothing.
  robot::Scene empty;
  empty.name = "empty";
  recordPostures(dir / "free.db", empty, {free_q, touching_q, free_q}, 50);
  const ParticipantResult clear = analyseSession(SessionReader(dir / "free.db"), 0.0);
  EXPECT_EQ(clear.e_coll, 0);
  EXPECT_EQ(clear.colliding_samples, 0);

  // The folder as a study: both sessions; a foreign file and a session with a damaged row
  // listed as skipped.
  {
    std::ofstream junk(dir / "junk.db");
    junk << "not a session";
  }
  std::filesystem::copy_file(dir / "free.db", dir / "damaged.db");
  {
    SqliteDatabase db((dir / "damaged.db").string(), 0x00000002);
    db.exec("UPDATE state SET q = x'0102' WHERE id = 5");
  }
  StudyOptions options;
  options.replay_interval = 0.0;
  const StudyResult study = analyseStudy(dir, options);
  ASSERT_EQ(study.participants.size(), 2U);
  EXPECT_EQ(study.participants[0].participant, "box");
  ASSERT_EQ(study.skipped.size(), 2U);
  EXPECT_EQ(study.skipped[0].rfind("damaged.db: ", 0), 0U) << study.skipped[0];
  EXPECT_EQ(study.skipped[1].rfind("junk.db: ", 0), 0U) << study.skipped[1];
  EXPECT_THROW(analyseStudy(dir / "none"), InputError);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace flexirob::app
