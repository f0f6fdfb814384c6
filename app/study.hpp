#pragma once
// Analysis across a folder of session recordings (a study, thesis Sect. 4.3.3-4.3.4, App. B.4):
// per-participant metrics, E_coll by replaying each recording against its scene in the collision
// world, k-means clustering of the q_fixed postures per training area from given initial centres
// (Tab. B.1), classical multi-dimensional scaling for a 2-D view of the postures (Fig. B.2), and
// the table of (in-)consistent cluster combinations (Tab. 4.1). Joint values in radians,
// positions in metres, times in seconds. The tables and their CSV columns: docs/STUDY.md.
#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "app/file_output.hpp"

namespace flexirob::app {

class SessionReader;

// --- Clustering and scaling (pure numerics).

struct KMeansResult {
  Eigen::MatrixXd centres;   ///< D x k final centres
  std::vector<int> labels;   ///< per point, the index of its centre
  std::vector<int> sizes;    ///< points per centre
  int iterations = 0;        ///< assignment rounds run
  bool converged = false;    ///< the assignment stopped changing within max_iterations
  double inertia = 0.0;      ///< Σ squared distances of the points to their centres
};

/// Lloyd's k-means [117] on the columns of `points` (D x P) from the given initial centres
/// (D x k, k >= 1): assign every point to its nearest centre (ties: the lower index), move each
/// centre to the mean of its points, repeat until no assignment changes. A centre that loses
/// all its points stays where it is (deterministic, as App. B.4 needs: random restarts "did not
/// reveal any reliable results"). Throws std::invalid_argument for mismatched or empty inputs.
KMeansResult kMeans(const Eigen::MatrixXd& points, const Eigen::MatrixXd& initial_centres, int max_iterations = 100);

/// Euclidean distances between the columns of `points` (D x P): P x P, symmetric, zero diagonal.
Eigen::MatrixXd pairwiseDistances(const Eigen::MatrixXd& points);

/// Classical (Torgerson) multi-dimensional scaling [118]: coordinates (dimensions x P) whose
/// Euclidean distances approximate `distances` (P x P, symmetric). B = −½ J D² J with the
/// centring J = I − 1/P; the coordinates are the top eigenvectors scaled by √λ (λ < 0 read as
/// 0). Exact for distances of points in `dimensions`-space (up to rotation, reflection and
/// translation). Sign convention: the largest-magnitude entry of each axis is positive.
Eigen::MatrixXd classicalMds(const Eigen::MatrixXd& distances, int dimensions = 2);

// --- The study.

/// Initial k-means centres of one training area: names ("L1", ...) and postures (first
/// `joints` joints each).
struct AreaClusterSeeds {
  int area = 0;
  std::vector<std::string> names;
  std::vector<Eigen::VectorXd> centres;
};

/// Tab. B.1: the thesis's initialization for the left (area 0: L1-L3) and right (area 1:
/// R1-R7) training areas of the LWR IV study, joints q1..q6.
std::vector<AreaClusterSeeds> thesisClusterSeeds();

/// Reads seeds from a JSON file: [{"area": 0, "name": "L1", "q": [q1, ..., q6]}, ...]. Throws
/// InputError with a one-line reason for an unreadable file, a wrong shape or non-finite values.
std::vector<AreaClusterSeeds> loadClusterSeeds(const std::filesystem::path& file);

/// What one recording contributes to the study.
struct ParticipantResult {
  std::string participant;  ///< the recording's participant, or its file name without extension
  std::string file;         ///< the recording's file name
  std::string robot, scene;
  std::string robot_urdf;  ///< the URDF text the recording stores (empty in older recordings)
  bool closed_cleanly = false;
  double duration_s = 0.0;
  int areas = 0;
  std::int64_t samples = 0;
  std::optional<double> e_task;        ///< [m] over executed motions with a reference (Eq. 3.20)
  std::optional<double> max_deviation; ///< [m] of teach-ins from their target (Sect. 5.2.2)
  std::optional<double> procrustes;    ///< [m] mean over teach-ins with a target
  std::optional<double> jerk_mean;     ///< [m/s³] mean over teach-ins
  std::int64_t e_coll_recorded = 0;    ///< contact events the session recorded
  /// E_coll by replay: contact events (a pair that starts touching) when the recorded q are
  /// replayed in the collision world of the recorded robot and scene; nullopt if not replayable.
  std::optional<std::int64_t> e_coll;
  std::int64_t colliding_samples = 0;  ///< replayed samples with a contact
  std::int64_t replayed_samples = 0;
  std::string replay_note;             ///< why not replayed, if not
  std::map<std::string, double> time_per_phase;  ///< [s] "STAGE" and "STAGE/SUB_STAGE"
  std::map<int, Eigen::VectorXd> q_fixed;        ///< per area index [rad]
  std::map<int, std::string> cluster;            ///< per clustered area: the cluster's name
};

struct StudyOptions {
  /// Initial centres per area; areas without seeds are not clustered.
  std::vector<AreaClusterSeeds> seeds = thesisClusterSeeds();
  int cluster_joints = 6;        ///< App. B.4: q7 only turns the tool, so q1..q6
  double replay_interval = 0.01; ///< [s] between replayed states (the workflow's check rate)
  /// A participant taught successfully (Sect. 4.3.4) with E_task at most this [m] (when an
  /// E_task is known) and E_coll = 0.
  double success_e_task = 0.01;
  std::function<void(const std::string&, double)> progress;  ///< (what, fraction); may be empty
  /// The robot whose postures `seeds` are (Tab. B.1: the LWR IV's); a study of another robot is
  /// not clustered against them. Empty: seeds for any robot (given with --centres).
  std::string seeds_robot = "lwr4";
};

/// One training area's clustering.
struct AreaClustering {
  int area = 0;
  std::vector<std::string> names;       ///< cluster names, as seeded
  std::vector<std::string> participants;  ///< those with a q_fixed in this area, in study order
  Eigen::MatrixXd postures;             ///< joints x P, the clustered q_fixed
  KMeansResult kmeans;
  Eigen::MatrixXd mds;                  ///< 2 x P, classical MDS of the postures
  Eigen::MatrixXd centre_mds;           ///< 2 x k, the centres placed in the same MDS plane
};

/// A row of Tab. 4.1.
struct Combination {
  std::string name;  ///< e.g. "L1-R6": the participant's cluster per clustered area
  int users = 0;
  int successful = 0;  ///< users with E_coll = 0 and E_task within the success bound
  std::optional<double> median_e_task;
  std::optional<double> median_e_coll;
  bool consistent = false;  ///< some user of this combination taught successfully
};

struct StudyResult {
  std::vector<ParticipantResult> participants;
  std::vector<std::string> skipped;  ///< "file: reason" for files that are no readable session
  /// "file: reason" for readable sessions left out of the clustering: postures of a robot other
  /// than the one most participants used (the first such in file order) are not comparable.
  std::vector<std::string> not_clustered;
  std::vector<AreaClustering> clusterings;
  std::vector<Combination> combinations;
  /// Why nothing was clustered although seeds were given (another robot's centres); empty otherwise.
  std::string clustering_note;
};

/// Metrics of one recording, E_coll replayed every `replay_interval` seconds of states.
ParticipantResult analyseSession(const SessionReader& reader, double replay_interval);

/// The files of `folder` a study reads: those ending in .flexirob, .db, .sqlite or .session,
/// sorted by name. Throws InputError if the folder does not exist.
std::vector<std::filesystem::path> studySessionFiles(const std::filesystem::path& folder);

/// Every session database in `folder` (files ending in .flexirob, .db, .sqlite or .session,
/// sorted by name), analysed, clustered and combined. Unreadable files are listed in `skipped`. Throws
/// InputError if the folder does not exist or holds no readable session.
StudyResult analyseStudy(const std::filesystem::path& folder, const StudyOptions& options = {});

/// Clusters and combinations of already analysed participants (fills their `cluster`).
void clusterStudy(StudyResult& study, const StudyOptions& options);

/// CSV files of every table: participants.csv, phases.csv, clusters_area<k>.csv,
/// centres_area<k>.csv and combinations.csv, written together with `along` (the plot) through
/// writeFilesTogether. Returns the CSV files written. Throws InputError if the folder cannot be
/// created or a file written, if one of `along` names a table's file, or if a table's file is one
/// of `inputs` (option, file: what the run reads), before anything is written.
std::vector<std::filesystem::path> writeStudyCsv(const StudyResult& study, const std::filesystem::path& folder,
                                                 const std::vector<OutputFile>& along = {},
                                                 const std::vector<std::pair<std::string, std::filesystem::path>>& inputs = {});

/// A line of text the scatter plot needs (a panel's title, a legend entry, the scale bar's
/// length). app/ draws no text: the caller prints the labels onto the image (flexirob-cli
/// through render::printLabels).
struct ScatterLabel {
  std::string text;   ///< UTF-8
  int x = 0;          ///< left end [px]
  int baseline = 0;   ///< base line [px from the top]
  int max_width = 0;  ///< cut with an ellipsis beyond this [px]
};

/// The MDS scatter plot of every clustered area side by side, as an RGBA image of width x
/// height pixels: per panel a title (the area, its participants), the postures as discs
/// coloured by cluster, the used centres as rings, and below them a legend (each cluster's
/// colour, name and members, the ring, a scale bar in rad) whose text is in `labels`.
struct ScatterImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgba;
  std::vector<ScatterLabel> labels;
};
ScatterImage renderMdsScatter(const StudyResult& study, int width = 480, int height = 360);

}  // namespace flexirob::app
