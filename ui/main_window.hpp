#pragma once
// The main window: the 3D view in the centre, the joint panel docked at the right, menus to
// choose robot and scene, and a status bar with the robot, the scene and the tip position.
#include <QMainWindow>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "render/world.hpp"
#include "robot/kinematics.hpp"
#include "robot/robot_model.hpp"
#include "robot/scene.hpp"

class QLabel;
class QMenu;

namespace flexirob::ui {

class JointPanel;
class OsgView;

class MainWindow : public QMainWindow {
  Q_OBJECT

 public:
  /// robot: built-in name or URDF path; scene: built-in name or scene file ("" = empty).
  /// Failures are reported in the status bar (the window then starts without robot or with the
  /// empty scene) rather than thrown.
  MainWindow(const std::string& robot, const std::string& scene, QWidget* parent = nullptr);
  ~MainWindow() override;

  /// Loads a robot (built-in name or URDF path). Returns false and shows why on failure; the
  /// previous robot stays.
  bool loadRobot(const std::string& name_or_path);
  /// Loads a scene (built-in name or file). Returns false and shows why on failure.
  bool loadScene(const std::string& name_or_path);
  /// Poses the robot (size dof(), radians / metres): view, joint panel and status bar.
  void setPosture(const Eigen::VectorXd& q);

  OsgView* view() const { return view_; }
  JointPanel* jointPanel() const { return joint_panel_; }
  render::World& world() { return world_; }
  const robot::RobotModel* robotModel() const { return model_.get(); }
  const robot::Kinematics* kinematics() const { return kinematics_.get(); }
  const robot::Scene& scene() const { return scene_; }
  QMenu* robotMenu() const { return robot_menu_; }
  QMenu* sceneMenu() const { return scene_menu_; }

 private:
  void buildMenus();
  void updateStatus();
  void reportError(const QString& what, const std::exception& error);

  render::World world_;
  std::unique_ptr<robot::RobotModel> model_;
  std::unique_ptr<robot::Kinematics> kinematics_;
  robot::Scene scene_;
  OsgView* view_ = nullptr;
  JointPanel* joint_panel_ = nullptr;
  QMenu* robot_menu_ = nullptr;
  QMenu* scene_menu_ = nullptr;
  QLabel* status_label_ = nullptr;
};

}  // namespace flexirob::ui
