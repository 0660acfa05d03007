// dribble_agent.cpp: a learned dribble called from a RoboCup 2D player, in the shape of a helios-base / agent2d
// behaviour. It builds the policy's 10-number observation from the world model, asks the exported policy
// (aacp_act) for an action type and its parameters, and turns them into this cycle's dash or kick, as
// robocup_dribble.skills does in the env.
//
// Build and run (from this folder; `sb3-aac c-header` prints where pip installed aacp.h):
//   c++ -std=c++11 -O2 -Wall -Wextra -I../../sb3_aac/runtime/c dribble_agent.cpp -o dribble_agent
//   ./dribble_agent dribbler.aacp
// (or `make`). So that this file builds on its own, the few librcsc classes it reads are stand-ins below with
// librcsc's names and accessors; in an agent2d team delete them, include <rcsc/player/player_agent.h> and
// <rcsc/common/server_param.h>, and keep Bhv_LearnedDribble. Compile aacp.h's implementation in exactly one .cpp
// file (#define AACP_IMPLEMENTATION before including it).

#define AACP_IMPLEMENTATION
#include "aacp.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

static const double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------- librcsc stand-ins
namespace rcsc {

struct Vector2D {
    double x, y;
    Vector2D(double x_ = 0.0, double y_ = 0.0) : x(x_), y(y_) {}
    double r() const { return std::sqrt(x * x + y * y); }
    double th() const { return std::atan2(y, x) * 180.0 / kPi; }  // degrees, as rcsc::AngleDeg
    Vector2D operator-(const Vector2D &o) const { return Vector2D(x - o.x, y - o.y); }
    Vector2D operator+(const Vector2D &o) const { return Vector2D(x + o.x, y + o.y); }
    Vector2D operator*(double s) const { return Vector2D(x * s, y * s); }
};

struct PlayerType {  // a heterogeneous type's parameters (rcsc::PlayerType)
    double player_decay, dash_power_rate, kickable_margin, kick_rand, kick_power_rate, player_size;
    double playerDecay() const { return player_decay; }
    double dashPowerRate() const { return dash_power_rate; }
    double kickableMargin() const { return kickable_margin; }
    double kickRand() const { return kick_rand; }
    double kickPowerRate() const { return kick_power_rate; }
    double playerSize() const { return player_size; }
};

struct ServerParam {  // rcsc::ServerParam::i(): the server's parameters (rcssserver 19 defaults)
    static const ServerParam &i() {
        static const ServerParam instance;
        return instance;
    }
    double ballSize() const { return 0.085; }
    double maxPower() const { return 100.0; }
    double maxDashPower() const { return 100.0; }
};

struct SelfObject {
    const PlayerType *type;
    Vector2D velocity;
    double body_deg;  // body direction, degrees
    const PlayerType &playerType() const { return *type; }
    const Vector2D &vel() const { return velocity; }
    double body() const { return body_deg; }  // rcsc returns an AngleDeg; .degree() gives this
};

struct BallObject {
    Vector2D relative, velocity;
    const Vector2D &rpos() const { return relative; }  // ball - self, field coordinates
    const Vector2D &vel() const { return velocity; }
};

struct WorldModel {
    SelfObject self_;
    BallObject ball_;
    const SelfObject &self() const { return self_; }
    const BallObject &ball() const { return ball_; }
};

struct PlayerAgent {  // prints the command instead of sending it to rcssserver
    WorldModel wm;
    const WorldModel &world() const { return wm; }
    bool doDash(double power, double dir) { return std::printf("command: (dash %.2f %.2f)\n", power, dir) > 0; }
    bool doKick(double power, double dir) { return std::printf("command: (kick %.2f %.2f)\n", power, dir) > 0; }
};

}  // namespace rcsc

// ---------------------------------------------------------------------------------- the behaviour
// The env's action types (robocup_dribble.skills.ACTION_NAMES) and their parameters.
enum { DASH_MAX = 0, KICK_VELOCITY = 1, KICK_POSITION = 2, KICK_ALIGN = 3 };

class Bhv_LearnedDribble {
public:
    // Load once (e.g. in the player's initImpl); a policy is not thread-safe, give each player thread its own.
    explicit Bhv_LearnedDribble(const char *path) : policy_(NULL) {
        aacp_error error;
        if (aacp_load_file(path, &policy_, &error) != AACP_OK) {
            std::fprintf(stderr, "%s\n", error.message);
            std::exit(1);
        }
        if (aacp_obs_size(policy_) != 10 || aacp_n_types(policy_) != 4) {
            std::fprintf(stderr, "%s is not a dribbling policy (10 inputs, 4 action types)\n", path);
            std::exit(1);
        }
    }
    ~Bhv_LearnedDribble() { aacp_free(policy_); }

    // robocup_dribble.task.observe: the player's type, then ball - player position and velocity, then its velocity.
    static void observation(const rcsc::WorldModel &wm, double obs[10]) {
        const rcsc::PlayerType &type = wm.self().playerType();
        const rcsc::Vector2D rvel = wm.ball().vel() - wm.self().vel();
        obs[0] = type.playerDecay();
        obs[1] = type.dashPowerRate();
        obs[2] = type.kickableMargin();
        obs[3] = type.kickRand();
        obs[4] = wm.ball().rpos().x;
        obs[5] = wm.ball().rpos().y;
        obs[6] = rvel.x;
        obs[7] = rvel.y;
        obs[8] = wm.self().vel().x;
        obs[9] = wm.self().vel().y;
    }

    bool execute(rcsc::PlayerAgent *agent) {
        const rcsc::WorldModel &wm = agent->world();
        double obs[10];
        aacp_action action;
        aacp_error error;
        observation(wm, obs);
        if (aacp_act(policy_, obs, 10, &action, &error) != AACP_OK) {
            std::fprintf(stderr, "%s\n", error.message);
            return false;
        }
        std::printf("decision: %lld", (long long)action.type);
        for (size_t j = 0; j < action.n_params; j++)
            std::printf(" %.17g", action.params[j]);
        std::printf("\n");
        return command(agent, action.type, action.params);
    }

private:
    // robocup_dribble.skills.command (rcssserver >= 14: dashes take a direction).
    bool command(rcsc::PlayerAgent *agent, int64_t type, const double *p) const {
        const rcsc::WorldModel &wm = agent->world();
        const double body = wm.self().body() * kPi / 180.0;
        const rcsc::Vector2D axis(std::cos(body), std::sin(body)), right(-axis.y, axis.x);  // +y when facing +x
        const rcsc::Vector2D rpos = wm.ball().rpos(), coast = wm.self().vel();
        switch (type) {
        case DASH_MAX:  // direction (deg)
            return agent->doDash(rcsc::ServerParam::i().maxDashPower(), p[0]);
        case KICK_VELOCITY:  // speed (m/cycle), direction (deg, relative to the body)
            return kickToward(agent, rcsc::Vector2D(std::cos(body + p[1] * kPi / 180.0), std::sin(body + p[1] * kPi / 180.0)) * p[0]);
        case KICK_POSITION:  // the ball at (x, y) of the body frame from the player's next position
            return kickToward(agent, coast + axis * p[0] + right * p[1] - rpos);
        default: {  // KICK_ALIGN: speed along the body, lateral offset from the player's next position
            const rcsc::Vector2D ahead = rpos - coast;
            const double lateral = ahead.x * right.x + ahead.y * right.y;
            return kickToward(agent, axis * p[0] + right * (p[1] - lateral));
        }
        }
    }

    // The kick that gives the ball `velocity` next cycle, or the closest the kick's power reaches (skills._kick_toward).
    static bool kickToward(rcsc::PlayerAgent *agent, const rcsc::Vector2D &velocity) {
        const rcsc::WorldModel &wm = agent->world();
        const rcsc::PlayerType &type = wm.self().playerType();
        const rcsc::Vector2D accel = velocity - wm.ball().vel();
        const double gap = wm.ball().rpos().r() - type.playerSize() - rcsc::ServerParam::i().ballSize();
        const double dir_diff = std::fabs(normalize(wm.ball().rpos().th() - wm.self().body())) * kPi / 180.0;
        // In agent2d this is wm.self().kickRate().
        const double rate = type.kickPowerRate() * (1.0 - 0.25 * dir_diff / kPi - 0.25 * gap / type.kickableMargin());
        const double max_power = rcsc::ServerParam::i().maxPower();
        const double power = rate > 0.0 ? std::fmin(accel.r() / rate, max_power) : max_power;
        return agent->doKick(power, normalize(accel.th() - wm.self().body()));
    }

    static double normalize(double deg) { return std::remainder(deg, 360.0); }  // to [-180, 180]

    aacp_policy *policy_;
};

int main(int argc, char **argv) {
    // One cycle of a heterogeneous player dribbling along +x, the ball just ahead to its right.
    const rcsc::PlayerType type = {0.42, 0.0062, 0.75, 0.05, 0.027, 0.3};
    rcsc::PlayerAgent agent;
    agent.wm.self_.type = &type;
    agent.wm.self_.velocity = rcsc::Vector2D(0.32, 0.02);
    agent.wm.self_.body_deg = 3.0;
    agent.wm.ball_.relative = rcsc::Vector2D(0.55, 0.18);
    agent.wm.ball_.velocity = rcsc::Vector2D(0.41, -0.03);

    Bhv_LearnedDribble dribble(argc > 1 ? argv[1] : "dribbler.aacp");
    double obs[10];
    Bhv_LearnedDribble::observation(agent.world(), obs);
    std::printf("observation:");
    for (int i = 0; i < 10; i++)
        std::printf(" %.17g", obs[i]);
    std::printf("\n");
    return dribble.execute(&agent) ? 0 : 1;
}
