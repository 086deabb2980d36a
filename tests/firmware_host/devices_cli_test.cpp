// `emf devices`: the listing by backend (with an emf virtual OpenNI2 device announced through
// EMF_VIRTUAL_DEVICES) and the --watch option.
#include <gtest/gtest.h>

#include "common/error.h"
#include "firmware_host/usb/usb_bus.h"
#include "test_support.h"

namespace emf::fw {
namespace {

std::string cli() { return std::string(EMF_CLI_PATH); }

TEST(DevicesCli, ListsBackendsAndVirtualDevices) {
  std::string out;
  ASSERT_EQ(test::runCommand(cli() + " devices --help", &out), 0);
  EXPECT_NE(out.find("usage: emf devices"), std::string::npos) << out;
  const std::string data = test::dataPath("redkitchen-0-299");
  ASSERT_EQ(test::runCommand("EMF_VIRTUAL_DEVICES=" + data + " " + cli() + " devices", &out), 0)
      << out;
  EXPECT_NE(out.find("USB RGB-D sensors (libusb):"), std::string::npos) << out;
#ifdef EMF_HAVE_OPENNI2
  EXPECT_NE(out.find("openni2:emf-virtual://" + data), std::string::npos) << out;
#endif
  EXPECT_NE(out.find("V4L2 video nodes:"), std::string::npos) << out;
  // The USB section lists exactly the known sensors libusb sees (or says why it cannot).
  bool have_bus = false;
  size_t expected = 0;
  try {
    expected = findSensors(openLibusbBus()->list()).size();
    have_bus = true;
  } catch (const IoError& e) {
    EXPECT_NE(out.find(std::string("(not available: ") + e.what()), std::string::npos) << out;
  }
  if (have_bus && expected == 0) {
    EXPECT_NE(out.find("(none found)"), std::string::npos) << out;
  }

  EXPECT_EQ(test::runCommand(cli() + " devices --watch soon", &out), 1);
  EXPECT_NE(out.find("--watch soon: expected seconds"), std::string::npos) << out;
  EXPECT_EQ(test::runCommand(cli() + " devices --wach 1", &out), 2);
  const int rc = test::runCommand(cli() + " devices --watch 0.2 --interval 0.05", &out);
  if (have_bus) {
    EXPECT_EQ(rc, 0) << out;
    EXPECT_NE(out.find("watching USB for 0.2 s"), std::string::npos) << out;
  } else {
    EXPECT_EQ(rc, 1) << out;
    EXPECT_NE(out.find("emf devices: cannot watch"), std::string::npos) << out;
  }
}

}  // namespace
}  // namespace emf::fw
