#include "ui/main_window.hpp"

#include <QAction>
#include <QActionGroup>
#include <QApplication>
#include <QDockWidget>
#include <QFileDialog>
#include <QLabel>
#include <QMenuBar>
#include <QScrollArea>
#include <QStatusBar>

#include "robot/resources.hpp"
#include "ui/joint_panel.hpp"
#include "ui/osg_view.hpp"

namespace flexirob::ui {

MainWindow::MainWindow(const std::string& robot, const std::string& scene, QWidget* parent) : QMainWindow(parent) {
  setWindowTitle(tr("FlexIRob"));
  view_ = new OsgView(this);
  setCentralWidget(view_);
  view_->setSceneRoot(world_.root());

  joint_panel_ = new JointPanel;
  auto* scroll = new QScrollArea;
  scroll->setWidget(joint_panel_);
  scroll->setWidgetResizable(true);
  auto* dock = new QDockWidget(tr("Joints"), this);
  dock->setObjectName(QStringLiteral("joints_dock"));
  dock->setWidget(scroll);
  dock->setFeatures(QDockWidget::DockWidgetMovable | QDockWidget::DockWidgetFloatable);
  addDockWidget(Qt::RightDockWidgetArea, dock);
  connect(joint_panel_, &JointPanel::postureChanged, this, [this](const Eigen::VectorXd& q) { setPosture(q); });

  status_label_ = new QLabel;
  statusBar()->addPermanentWidget(status_label_);
  buildMenus();

  loadScene(scene);
  // Without an explicit robot, the robot the scene was made for.
  loadRobot(robot.empty() ? (scene_.robot.empty() ? std::string("lwr4") : scene_.robot) : robot);
  resize(1280, 800);
}

MainWindow::~MainWindow() = default;

void MainWindow::reportError(const QString& what, const std::exception& error) {
  const QString message = what + QStringLiteral(": ") + QString::fromUtf8(error.what());
  statusBar()->showMessage(message, 15000);
  qWarning("%s", qPrintable(message));
}

bool MainWindow::loadRobot(const std::string& name_or_path) {
  try {
    auto model = std::make_unique<robot::RobotModel>(robot::RobotModel::fromUrdfFile(resolveRobotPath(name_or_path)));
    auto kinematics = std::make_unique<robot::Kinematics>(*model);
    world_.setRobot(*model);
    model_ = std::move(model);
    kinematics_ = std::move(kinematics);
  } catch (const std::exception& error) {
    reportError(tr("Cannot load robot '%1'").arg(QString::fromStdString(name_or_path)), error);
    return false;
  }
  // Start posture: the scene's, if it was made for a robot with this many joints.
  Eigen::VectorXd q = model_->midPosture();
  if (scene_.home_posture && scene_.home_posture->size() == model_->dof()) q = *scene_.home_posture;
  joint_panel_->setRobot(*model_, q);
  setPosture(joint_panel_->posture());
  view_->setHomeCamera(world_.defaultCamera(static_cast<double>(view_->width()) / std::max(1, view_->height())));
  for (QAction* action : robot_menu_->actions()) {
    action->setChecked(action->data().toString().toStdString() == name_or_path);
  }
  return true;
}

bool MainWindow::loadScene(const std::string& name_or_path) {
  try {
    robot::Scene scene = robot::loadScene(name_or_path);
    world_.setScene(scene);
    scene_ = std::move(scene);
  } catch (const std::exception& error) {
    reportError(tr("Cannot load scene '%1'").arg(QString::fromStdString(name_or_path)), error);
    return false;
  }
  if (model_ && scene_.home_posture && scene_.home_posture->size() == model_->dof()) {
    joint_panel_->setPosture(*scene_.home_posture);
    setPosture(joint_panel_->posture());
  }
  view_->setHomeCamera(world_.defaultCamera(static_cast<double>(view_->width()) / std::max(1, view_->height())));
  const std::string shown = name_or_path.empty() ? std::string("empty") : name_or_path;
  for (QAction* action : scene_menu_->actions()) action->setChecked(action->data().toString().toStdString() == shown);
  updateStatus();
  return true;
}

void MainWindow::setPosture(const Eigen::VectorXd& q) {
  if (!model_ || q.size() != model_->dof()) return;
  kinematics_->update(q);
  world_.robot()->setPosture(*kinematics_);
  if (joint_panel_->posture() != q) joint_panel_->setPosture(q);
  updateStatus();
  view_->update();
}

void MainWindow::updateStatus() {
  QString text;
  if (model_) {
    const Eigen::Vector3d p = kinematics_->p_WT();
    text = tr("robot %1 (%2 joints)   tip %3 at (%4, %5, %6) m   ")
               .arg(QString::fromStdString(model_->name()))
               .arg(model_->dof())
               .arg(QString::fromStdString(model_->tipLink()))
               .arg(p.x(), 0, 'f', 3)
               .arg(p.y(), 0, 'f', 3)
               .arg(p.z(), 0, 'f', 3);
  } else {
    text = tr("no robot   ");
  }
  text += tr("scene %1").arg(QString::fromStdString(scene_.name.empty() ? std::string("empty") : scene_.name));
  status_label_->setText(text);
}

void MainWindow::buildMenus() {
  QMenu* file = menuBar()->addMenu(tr("&File"));
  file->addAction(tr("Open robot &URDF…"), this, [this] {
    const QString path = QFileDialog::getOpenFileName(this, tr("Open robot description"), QString(),
                                                      tr("URDF (*.urdf *.xml);;All files (*)"));
    if (!path.isEmpty()) loadRobot(path.toStdString());
  });
  file->addAction(tr("Open &scene…"), this, [this] {
    const QString path = QFileDialog::getOpenFileName(this, tr("Open scene"), QString(),
                                                      tr("Scenes (*.yaml *.yml);;All files (*)"));
    if (!path.isEmpty()) loadScene(path.toStdString());
  });
  file->addAction(tr("Save &screenshot…"), this, [this] {
    const QString path = QFileDialog::getSaveFileName(this, tr("Save screenshot"), QStringLiteral("flexirob.png"),
                                                      tr("PNG (*.png)"));
    if (!path.isEmpty() && !grab().save(path)) statusBar()->showMessage(tr("Cannot write %1").arg(path), 10000);
  });
  file->addSeparator();
  file->addAction(tr("&Quit"), QKeySequence::Quit, qApp, &QApplication::quit);

  robot_menu_ = menuBar()->addMenu(tr("&Robot"));
  auto* robots = new QActionGroup(this);
  for (const std::string& name : builtinRobotNames()) {
    QAction* action = robot_menu_->addAction(QString::fromStdString(name), this, [this, name] { loadRobot(name); });
    action->setData(QString::fromStdString(name));
    action->setCheckable(true);
    robots->addAction(action);
  }

  scene_menu_ = menuBar()->addMenu(tr("&Scene"));
  auto* scenes = new QActionGroup(this);
  for (const std::string& name : robot::builtinSceneNames()) {
    QAction* action = scene_menu_->addAction(QString::fromStdString(name), this, [this, name] { loadScene(name); });
    action->setData(QString::fromStdString(name));
    action->setCheckable(true);
    scenes->addAction(action);
  }

  QMenu* view = menuBar()->addMenu(tr("&View"));
  view->addAction(tr("&Reset camera"), QKeySequence(Qt::Key_Home), view_, &OsgView::resetCamera);
  QAction* grid = view->addAction(tr("Ground &grid"));
  grid->setCheckable(true);
  grid->setChecked(true);
  connect(grid, &QAction::toggled, this, [this](bool on) {
    world_.setGridVisible(on);
    view_->update();
  });
  QMenu* help = menuBar()->addMenu(tr("&Help"));
  help->addAction(tr("&Mouse"), this, [this] {
    statusBar()->showMessage(
        tr("Left drag: orbit   Middle or Shift+left drag: pan   Right drag or wheel: zoom   Double click: home view"),
        15000);
  });
}

}  // namespace flexirob::ui
