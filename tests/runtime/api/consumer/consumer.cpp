// Casts one ray at the unit sphere through the installed API and prints the distance (expected 2).
#include <prt/pointrt.h>

#include <cstdio>
#include <vector>

int main(int argc, char** argv) {
    if (argc != 2) return 2;
    try {
        pointrt::Options options;
        options.backend = "cpu";
        pointrt::Scene scene = pointrt::Scene::open(argv[1], options);
        std::vector<pointrt::Ray> rays(1);
        rays[0].origin = {0, 0, 3};
        rays[0].direction = {0, 0, -1};
        const pointrt::Hit hit = scene.cast(rays)[0];
        std::printf("pointrt %s: hit %d t %.3f\n", pointrt::version().c_str(), hit.hit ? 1 : 0, hit.t);
        return hit.hit && hit.t > 1.99f && hit.t < 2.01f ? 0 : 1;
    } catch (const pointrt::Error& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
}
