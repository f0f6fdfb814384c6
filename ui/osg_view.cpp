#include "ui/osg_view.hpp"

#include <QMouseEvent>
#include <QOpenGLContext>
#include <QWheelEvent>
#include <algorithm>
#include <osgUtil/IntersectionVisitor>
#include <osgUtil/LineSegmentIntersector>

#include "render/shapes.hpp"
#include "render/world.hpp"

namespace flexirob::ui {

OsgView::OsgView(QWidget* parent)
    : QOpenGLWidget(parent), viewer_(new osgViewer::Viewer), manipulator_(new osgGA::OrbitManipulator) {
  setMinimumSize(320, 240);
  setFocusPolicy(Qt::StrongFocus);
  setMouseTracking(false);
  viewer_->setThreadingModel(osgViewer::Viewer::SingleThreaded);
  window_ = viewer_->setUpViewerAsEmbeddedInWindow(0, 0, 800, 600);
  // Qt's mouse y grows downwards; tell OSG so that orbiting follows the hand.
  events()->getCurrentEventState()->setMouseYOrientation(osgGA::GUIEventAdapter::Y_INCREASING_DOWNWARDS);
  viewer_->setLightingMode(osg::View::NO_LIGHT);  // the world brings its own lights
  viewer_->setKeyEventSetsDone(0);                 // Escape must not end the viewer
  const Eigen::Vector4f background = render::Palette::background();
  viewer_->getCamera()->setClearColor(osg::Vec4(background[0], background[1], background[2], background[3]));
  manipulator_->setAllowThrow(false);
  viewer_->setCameraManipulator(manipulator_, false);
}

OsgView::~OsgView() {
  // OSG frees its GL objects while our context is current.
  makeCurrent();
  viewer_ = nullptr;
  window_ = nullptr;
  doneCurrent();
}

void OsgView::setSceneRoot(osg::Node* root) {
  viewer_->setSceneData(root);
  update();
}

void OsgView::setHomeCamera(const render::CameraPose& camera) {
  home_ = camera;
  resetCamera();
}

void OsgView::resetCamera() {
  manipulator_->setHomePosition(render::toOsg(home_.eye_W), render::toOsg(home_.center_W),
                                render::toOsg(home_.up_W), false);
  manipulator_->home(0.0);
  resizeGL(width(), height());  // field of view of the home camera
  update();
}

render::CameraPose OsgView::currentCamera() const {
  osg::Vec3d eye;
  osg::Vec3d center;
  osg::Vec3d up;
  manipulator_->getTransformation(eye, center, up);
  render::CameraPose camera = home_;
  camera.eye_W = Eigen::Vector3d(eye.x(), eye.y(), eye.z());
  camera.center_W = Eigen::Vector3d(center.x(), center.y(), center.z());
  camera.up_W = Eigen::Vector3d(up.x(), up.y(), up.z());
  return camera;
}

void OsgView::initializeGL() {}

void OsgView::resizeGL(int width, int height) {
  const int w = std::max(1, static_cast<int>(width * scale()));
  const int h = std::max(1, static_cast<int>(height * scale()));
  window_->resized(0, 0, w, h);
  events()->windowResize(0, 0, w, h);
  osg::Camera* camera = viewer_->getCamera();
  camera->setViewport(0, 0, w, h);
  camera->setProjectionMatrixAsPerspective(home_.fovy_deg, static_cast<double>(w) / h, 0.01, 100.0);
}

void OsgView::paintGL() {
  // Platforms without OpenGL (e.g. Qt's offscreen platform) give no context: draw nothing.
  if (context() == nullptr || !context()->isValid()) return;
  // QOpenGLWidget draws into its own framebuffer object, not into framebuffer 0.
  window_->setDefaultFboId(defaultFramebufferObject());
  viewer_->frame();
  ++frames_;
}

int OsgView::osgButton(const QMouseEvent* event) const {
  switch (event->button()) {
    case Qt::LeftButton:
      return (event->modifiers() & Qt::ShiftModifier) ? 2 : 1;  // Shift + left pans
    case Qt::MiddleButton:
      return 2;
    case Qt::RightButton:
      return 3;
    default:
      return 0;
  }
}

int OsgView::pick(const QPointF& position, const std::vector<osg::Node*>& bodies, Eigen::Vector3d& point_W) {
  const QPointF p = position * scale();
  // OSG's window coordinates grow upwards.
  const double x = p.x();
  const double y = height() * scale() - p.y();
  osg::ref_ptr<osgUtil::LineSegmentIntersector> intersector =
      new osgUtil::LineSegmentIntersector(osgUtil::Intersector::WINDOW, x, y);
  osgUtil::IntersectionVisitor visitor(intersector.get());
  viewer_->getCamera()->accept(visitor);
  for (const auto& hit : intersector->getIntersections()) {  // sorted nearest first
    for (osg::Node* node : hit.nodePath) {
      const auto found = std::find(bodies.begin(), bodies.end(), node);
      if (found != bodies.end()) {
        const osg::Vec3d w = hit.getWorldIntersectPoint();
        point_W = Eigen::Vector3d(w.x(), w.y(), w.z());
        return static_cast<int>(found - bodies.begin());
      }
    }
  }
  return -1;
}

void OsgView::ray(const QPointF& position, Eigen::Vector3d& origin_W, Eigen::Vector3d& direction_W) const {
  const osg::Camera* camera = viewer_->getCamera();
  const osg::Matrixd vpw = camera->getViewMatrix() * camera->getProjectionMatrix() *
                           camera->getViewport()->computeWindowMatrix();
  const osg::Matrixd inverse = osg::Matrixd::inverse(vpw);
  const QPointF p = position * scale();
  const double x = p.x();
  const double y = height() * scale() - p.y();
  const osg::Vec3d near_W = osg::Vec3d(x, y, 0.0) * inverse;
  const osg::Vec3d far_W = osg::Vec3d(x, y, 1.0) * inverse;
  origin_W = Eigen::Vector3d(near_W.x(), near_W.y(), near_W.z());
  direction_W = Eigen::Vector3d(far_W.x() - near_W.x(), far_W.y() - near_W.y(), far_W.z() - near_W.z()).normalized();
}

Eigen::Vector3d OsgView::viewDirection() const {
  const render::CameraPose camera = currentCamera();
  return (camera.center_W - camera.eye_W).normalized();
}

void OsgView::mousePressEvent(QMouseEvent* event) {
  if (control_click_ && event->button() == Qt::LeftButton && (event->modifiers() & Qt::ControlModifier)) {
    control_clicking_ = true;
    control_click_(event->position());
    update();
    return;
  }
  if (grabber_ != nullptr && event->button() == Qt::LeftButton && !(event->modifiers() & Qt::ShiftModifier) &&
      grabber_->press(event->position())) {
    grabbing_ = true;
    update();
    return;
  }
  const QPointF p = event->position() * scale();
  events()->mouseButtonPress(static_cast<float>(p.x()), static_cast<float>(p.y()),
                             static_cast<unsigned int>(osgButton(event)));
  update();
}

void OsgView::mouseReleaseEvent(QMouseEvent* event) {
  if (control_clicking_) {
    if (event->button() == Qt::LeftButton) control_clicking_ = false;
    return;
  }
  if (grabbing_) {
    if (event->button() == Qt::LeftButton) {
      grabbing_ = false;
      if (grabber_ != nullptr) grabber_->release();
    }
    update();
    return;
  }
  const QPointF p = event->position() * scale();
  events()->mouseButtonRelease(static_cast<float>(p.x()), static_cast<float>(p.y()),
                               static_cast<unsigned int>(osgButton(event)));
  update();
}

void OsgView::mouseMoveEvent(QMouseEvent* event) {
  if (control_clicking_) return;
  if (grabbing_) {
    if (grabber_ != nullptr) grabber_->move(event->position());
    update();
    return;
  }
  const QPointF p = event->position() * scale();
  events()->mouseMotion(static_cast<float>(p.x()), static_cast<float>(p.y()));
  update();
}

void OsgView::mouseDoubleClickEvent(QMouseEvent* event) {
  // A double click brings back the home view.
  if (event->button() == Qt::LeftButton) resetCamera();
}

void OsgView::wheelEvent(QWheelEvent* event) {
  const int delta = event->angleDelta().y();
  // Wheel forward zooms in. OSG's orbit manipulator zooms in on SCROLL_DOWN.
  if (delta != 0) {
    events()->mouseScroll(delta > 0 ? osgGA::GUIEventAdapter::SCROLL_DOWN : osgGA::GUIEventAdapter::SCROLL_UP);
  }
  update();
}

}  // namespace flexirob::ui
