// The in-process CAN bus: delivery to the other ports, fault injection, bus states (plsa/can/can_transport.hpp).
#include <gtest/gtest.h>

#include <chrono>

#include "plsa/can/can_transport.hpp"

using namespace plsa::can;
using namespace std::chrono_literals;

TEST(InProcessBus, DeliversToOthersAndInjectsFaults) {
  auto bus = InProcessBus::create();
  auto a = bus->connect(), b = bus->connect(4);
  CanFrame f;
  f.id = 0x123;
  f.dlc = 2;
  f.data[0] = 0xAB;
  ASSERT_EQ(a->send(f), TransportStatus::kOk);
  CanFrame got;
  ASSERT_EQ(b->receive(got, 10ms), TransportStatus::kOk);
  EXPECT_EQ(got.data[0], 0xAB);
  EXPECT_EQ(a->receive(got, 1ms), TransportStatus::kTimeout);  // not its own
  for (int i = 0; i < 6; ++i) a->send(f);
  EXPECT_EQ(b->stats().overflows, 2u);
  while (b->receive(got, 0us) == TransportStatus::kOk) {}
  bus->setFaults({1.0, 0.0, 0us, 3});
  a->send(f);
  EXPECT_EQ(b->receive(got, 2ms), TransportStatus::kTimeout);
  EXPECT_EQ(b->stats().dropped, 1u);
  bus->setFaults({0.0, 1.0, 0us, 3});
  a->send(f);
  ASSERT_EQ(b->receive(got, 10ms), TransportStatus::kOk);
  EXPECT_NE(got.data, f.data);
  bus->setFaults({0.0, 0.0, 20ms, 3});
  a->send(f);
  EXPECT_EQ(b->receive(got, 2ms), TransportStatus::kTimeout);  // delayed, not lost
  EXPECT_EQ(b->receive(got, 100ms), TransportStatus::kOk);
  bus->setBusState(BusState::kBusOff);
  EXPECT_EQ(a->send(f), TransportStatus::kBusOff);
  f.dlc = 9;
  EXPECT_EQ(a->send(f), TransportStatus::kBadFrame);
}
