#include "ui/osg_view.hpp"

#include <optional>

#include <QMouseEvent>
#include <QOffscreenSurface>
#include <QOpenGLContext>
#include <QOpenGLFramebufferObject>
#include <QOpenGLFunctions>
#include <QPainter>
#include <QWheelEvent>
#include <algorithm>
#include <osgUtil/IntersectionVisitor>
#include <osgUtil/LineSegmentIntersector>

#include "render/shapes.hpp"
#include "render/world.hpp"

namespace flexirob::ui {

// OSG's orbit, pan and zoom, with the eye kept above a floor: a move that would take it below
// (and lower than it was) is taken back whole.
class AboveFloorManipulator : public osgGA::OrbitManipulator {
 public:
  void setFloor(std::optional<double> floor_z) { floor_z_ = floor_z; }

 protected:
  bool performMovement() override {
    return keptAboveFloor([this] { return osgGA::OrbitManipulator::performMovement(); });
  }
  bool handleMouseWheel(const osgGA::GUIEventAdapter& event, osgGA::GUIActionAdapter& action) override {
    return keptAboveFloor([&] { return osgGA::OrbitManipulator::handleMouseWheel(event, action); });
  }

 private:
  // A hand's width above the table top: at the floor itself the view would graze the grid.
  static constexpr double kClearance = 0.05;  // [m]

  double eyeHeight() const {
    osg::Vec3d eye;
    osg::Vec3d center;
    osg::Vec3d up;
    getTransformation(eye, center, up);
    return eye.z();
  }

  template <typename Move>
  bool keptAboveFloor(Move move) {
    if (!floor_z_) return move();
    const osg::Vec3d center = _center;
    const osg::Quat rotation = _rotation;
    const double distance = _distance;
    const double before = eyeHeight();
    const bool handled = move();
    const double after = eyeHeight();
    if (after < *floor_z_ + kClearance && after < before) {
      _center = center;
      _rotation = rotation;
      _distance = distance;
    }
    return handled;
  }

  std::optional<double> floor_z_;
};

OsgView::OsgView(QWidget* parent)
    : QWidget(parent), viewer_(new osgViewer::Viewer), manipulator_(new AboveFloorManipulator) {
  // Beside the docks' own minimum widths the window still fits an 800 px screen.
  setMinimumSize(300, 200);
  // Every pixel comes from the frame: Qt need not clear behind it.
  setAttribute(Qt::WA_OpaquePaintEvent);
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
  const bool current = makeContextCurrent();
  viewer_ = nullptr;
  window_ = nullptr;
  framebuffer_.reset();
  resolved_.reset();
  if (current) context_->doneCurrent();
}

void OsgView::requestFrame() {
  frame_due_ = true;
  update();
}

void OsgView::setSceneRoot(osg::Node* root) {
  viewer_->setSceneData(root);
  requestFrame();
}

void OsgView::setHomeCamera(const render::CameraPose& camera) {
  home_ = camera;
  resetCamera();
}

void OsgView::setFloor(std::optional<double> floor_z) { manipulator_->setFloor(floor_z); }

void OsgView::resetCamera() {
  manipulator_->setHomePosition(render::toOsg(home_.eye_W), render::toOsg(home_.center_W),
                                render::toOsg(home_.up_W), false);
  manipulator_->home(0.0);
  updateProjection();  // field of view of the home camera
  requestFrame();
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

QSize OsgView::pixelSize() const {
  return {std::max(1, static_cast<int>(width() * scale())), std::max(1, static_cast<int>(height() * scale()))};
}

void OsgView::updateProjection() {
  const int w = pixelSize().width();
  const int h = pixelSize().height();
  window_->resized(0, 0, w, h);
  events()->windowResize(0, 0, w, h);
  osg::Camera* camera = viewer_->getCamera();
  camera->setViewport(0, 0, w, h);
  camera->setProjectionMatrixAsPerspective(home_.fovy_deg, static_cast<double>(w) / h, 0.01, 100.0);
}

void OsgView::resizeEvent(QResizeEvent* event) {
  QWidget::resizeEvent(event);
  updateProjection();
  frame_due_ = true;
}

bool OsgView::makeContextCurrent() {
  if (gl_failed_) return false;
  if (!context_) {
    // Platforms without OpenGL (e.g. Qt's offscreen platform) give no context: draw nothing.
    context_ = std::make_unique<QOpenGLContext>();
    context_->setFormat(QSurfaceFormat::defaultFormat());
    surface_ = std::make_unique<QOffscreenSurface>();
    if (!context_->create()) {
      gl_failed_ = true;
      return false;
    }
    surface_->setFormat(context_->format());
    surface_->create();
  }
  if (!surface_->isValid() || !context_->makeCurrent(surface_.get())) {
    gl_failed_ = true;
    return false;
  }
  return true;
}

void OsgView::renderFrame() {
  if (!makeContextCurrent()) return;
  const QSize size = pixelSize();
  if (!framebuffer_ || framebuffer_->size() != size) {
    QOpenGLFramebufferObjectFormat format;
    format.setAttachment(QOpenGLFramebufferObject::CombinedDepthStencil);
    format.setSamples(std::max(0, context_->format().samples()));
    framebuffer_ = std::make_unique<QOpenGLFramebufferObject>(size, format);
    resolved_.reset();
    if (format.samples() > 0) resolved_ = std::make_unique<QOpenGLFramebufferObject>(size);
    // One buffer for the life of this size: a fresh megabyte per frame would be mapped and
    // unmapped by the allocator every frame, and the page-table lock that takes stalls the
    // control thread.
    frame_ = QImage(size, QImage::Format_RGBA8888_Premultiplied);
    frame_.setDevicePixelRatio(scale());
    frame_.fill(palette().window().color());
  }
  framebuffer_->bind();
  window_->setDefaultFboId(framebuffer_->handle());
  viewer_->frame();
  QOpenGLFramebufferObject* source = framebuffer_.get();
  if (resolved_) {
    QOpenGLFramebufferObject::blitFramebuffer(resolved_.get(), framebuffer_.get());
    source = resolved_.get();
  }
  source->bind();
  QOpenGLFunctions* gl = context_->functions();
  gl->glPixelStorei(GL_PACK_ALIGNMENT, 4);
  gl->glReadPixels(0, 0, size.width(), size.height(), GL_RGBA, GL_UNSIGNED_BYTE, frame_.bits());
  source->release();
  context_->doneCurrent();
  // OpenGL's rows run bottom-up, the image's top-down.
  const auto row_bytes = static_cast<std::size_t>(frame_.bytesPerLine());
  for (int top = 0, bottom = size.height() - 1; top < bottom; ++top, --bottom) {
    std::swap_ranges(frame_.scanLine(top), frame_.scanLine(top) + row_bytes, frame_.scanLine(bottom));
  }
  frame_due_ = false;
  ++frames_;
}

QImage OsgView::grabFramebuffer() {
  renderFrame();
  return frame_;
}

void OsgView::paintEvent(QPaintEvent* /*event*/) {
  const QSize size = pixelSize();
  if (frame_due_ || frame_.size() != size) renderFrame();
  QPainter painter(this);
  if (frame_.isNull()) {
    painter.fillRect(rect(), palette().window());
    painter.drawText(rect(), Qt::AlignCenter, tr("No OpenGL on this platform: the 3D view cannot draw."));
    return;
  }
  painter.drawImage(QPointF(0.0, 0.0), frame_);
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
    requestFrame();
    return;
  }
  if (grabber_ != nullptr && event->button() == Qt::LeftButton && !(event->modifiers() & Qt::ShiftModifier) &&
      grabber_->press(event->position())) {
    grabbing_ = true;
    requestFrame();
    return;
  }
  const QPointF p = event->position() * scale();
  events()->mouseButtonPress(static_cast<float>(p.x()), static_cast<float>(p.y()),
                             static_cast<unsigned int>(osgButton(event)));
  requestFrame();
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
    requestFrame();
    return;
  }
  const QPointF p = event->position() * scale();
  events()->mouseButtonRelease(static_cast<float>(p.x()), static_cast<float>(p.y()),
                               static_cast<unsigned int>(osgButton(event)));
  requestFrame();
}

void OsgView::mouseMoveEvent(QMouseEvent* event) {
  if (control_clicking_) return;
  if (grabbing_) {
    if (grabber_ != nullptr) grabber_->move(event->position());
    requestFrame();
    return;
  }
  const QPointF p = event->position() * scale();
  events()->mouseMotion(static_cast<float>(p.x()), static_cast<float>(p.y()));
  requestFrame();
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
  requestFrame();
}

}  // namespace flexirob::ui
