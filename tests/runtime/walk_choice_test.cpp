// rt::WalkChoice: the CUDA backend's choice between the ISO walk with macro-regions and the walk
// compiled without them (BackendOptions::cuda_iso_walk "auto"), driven here by made-up frame times.
#include "prt/runtime/walk_choice.h"

#include <gtest/gtest.h>

#include <vector>

namespace {

using prt::rt::WalkChoice;

/// Runs `frames` frames of kind `key`, kernel k taking ms[k]; returns the kernels run in order.
std::vector<int> run(WalkChoice& c, const WalkChoice::Key& key, int frames, const float ms[2]) {
    std::vector<int> ran;
    for (int i = 0; i < frames; ++i) {
        const int k = c.next(key);
        ran.push_back(k);
        c.record(ms[k]);
    }
    return ran;
}

int count(const std::vector<int>& ran, int k, std::size_t from = 0) {
    int n = 0;
    for (std::size_t i = from; i < ran.size(); ++i) n += ran[i] == k ? 1 : 0;
    return n;
}

TEST(WalkChoice, TrialsThenTheFasterWithARecheck) {
    for (const int faster : {0, 1}) {
        WalkChoice c;
        const WalkChoice::Key key{1, 1024, 1024};
        float ms[2] = {1.0f, 1.0f};
        ms[faster] = 0.9f;
        const std::vector<int> ran = run(c, key, 200, ms);
        // frame 0 untimed on the walk with regions, then 0, 1, 0, 1
        EXPECT_EQ((std::vector<int>(ran.begin(), ran.begin() + 5)), (std::vector<int>{0, 0, 1, 0, 1}));
        EXPECT_EQ(c.chosen(key), faster);
        // after the trials: the slower one only on frames 64, 128, 192
        EXPECT_EQ(count(ran, 1 - faster, 5), 3) << "faster " << faster;
        EXPECT_EQ(ran[64], 1 - faster);
        EXPECT_EQ(ran[65], faster);
    }
}

TEST(WalkChoice, FollowsAViewThatChangesAndIgnoresNoise) {
    WalkChoice c;
    const WalkChoice::Key key{1, 640, 480};
    const float plain_faster[2] = {1.0f, 0.8f};
    run(c, key, 10, plain_faster);
    EXPECT_EQ(c.chosen(key), 1);
    // The view moves where the regions pay: the next recheck (frame 64) switches back.
    const float regions_faster[2] = {0.7f, 1.0f};
    const std::vector<int> ran = run(c, key, 60, regions_faster);
    EXPECT_EQ(c.chosen(key), 0);
    EXPECT_EQ(ran.back(), 0);
    // Within the 2 % margin the choice stays.
    const float close[2] = {0.70f, 0.69f};
    run(c, key, 200, close);
    EXPECT_EQ(c.chosen(key), 0);
}

TEST(WalkChoice, KindsAreApartAndTheColdFrameIsNotTimed) {
    WalkChoice c;
    const WalkChoice::Key a{1, 64, 64}, b{2, 64, 64};
    // The first frame of a kind runs the walk with regions whatever it takes.
    EXPECT_EQ(c.next(a), 0);
    c.record(100.0f);  // cold: ignored
    const float ms[2] = {1.0f, 2.0f};
    run(c, a, 10, ms);
    EXPECT_EQ(c.chosen(a), 0);
    const float other[2] = {2.0f, 1.0f};
    run(c, b, 10, other);
    EXPECT_EQ(c.chosen(b), 1);
    EXPECT_EQ(c.chosen(a), 0);
    // A record without next() and a frame with no time change nothing.
    c.record(0.1f);
    EXPECT_EQ(c.next(a), c.chosen(a));
    c.record(0.0f);
    EXPECT_EQ(c.chosen(a), 0);
    // Kinds beyond k_max_kinds push out the oldest, which then starts over.
    for (std::uint32_t k = 0; k < WalkChoice::k_max_kinds; ++k) run(c, {100 + k, 64, 64}, 1, ms);
    EXPECT_EQ(c.chosen(b), 0) << "b was pushed out: its trials start again";
}

}  // namespace
