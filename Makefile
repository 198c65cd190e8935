# luv-physics -- rigid spheres in a block world, written as the literate page physics.org.
# Run 'make help' for the targets.  GNU Make; Debian 12 with sbcl, emacs-nox, cl-fiveam, slime.

EMACS  ?= emacs
SBCL   ?= sbcl
# compiling the kernels' feature variants needs more than SBCL's default 1 GB heap
HEAP   ?= 4Gb
ANCHOR ?=
SEED   ?= 1
COUNT  ?= 150
# make fuzz runs 1200 sequences unless COUNT is given: the 150 above is make mutate's default
FUZZ_COUNT := $(if $(filter command line environment,$(origin COUNT)),$(COUNT),1200)

ORG    := physics.org
OUT    := tangled/physics.lisp tangled/physics-simd.lisp tangled/workshop.lisp tests/physics-tests.lisp
LISP   := $(SBCL) --dynamic-space-size $(HEAP) --noinform --non-interactive --no-sysinit --no-userinit

.PHONY: help setup tangle check-tangle check-anchors test fresh-compile-log editor-test demo load-time bench bench-workers bench-rollback bench-snapshots count-snapshots fuzz-snapshots bench-peers bench-against bench-joint-grid bench-pyramid count-against count-features count-pyramid report report-peers heaps mutate mutate-splice prose-count html view pictures fuzz soak clean
.NOTPARALLEL:

help:
	@echo "make demo           install what is missing (as root), tangle, run the default scene;"
	@echo "                    SCENE=name runs another scene of the page (basin, pile, fountain, lava,"
	@echo "                    player, awake-basin)"
	@echo "                    SAVE=file also writes the world the scene ends with (write-physics-world)"
	@echo "make test           check tangling and anchors, then run every claim: a line per part of the"
	@echo "                    page, the ten slowest claims; report/compile.log and report/claims.log"
	@echo "                    hold what the compiler and the claims printed"
	@echo "make test ANCHOR=ID run only the claims of section ID (without the editor checks)"
	@echo "make editor-test    Emacs with SLIME against a live image: jumps, edit buffers, reload"
	@echo "make setup          install what the page needs if missing (apt-get, as root): sbcl, emacs-nox,"
	@echo "                    cl-fiveam, slime, elpa-htmlize, libjs-three; chromium, imagemagick for the browser claims"
	@echo "make tangle         write $(OUT) from $(ORG), each only if its text changed"
	@echo "make check-tangle   do the generated files equal what $(ORG) tangles to?"
	@echo "make check-anchors  links, anchors, claim blocks and docstrings of $(ORG)"
	@echo "make load-time      the engine's load: compiled from an empty cache, then loaded compiled,"
	@echo "                    in fresh SBCLs, with the workshop's compile beside it; table into $(ORG)"
	@echo "make bench          measure the basin per kernel family and the queries; write the tables into $(ORG)"
	@echo "make bench-workers  the basin with one worker and with two, stepped in turn; table into $(ORG)"
	@echo "make bench-rollback an 8-step rollback at 1000 balls (restore and 8 steps) against a 60 Hz frame"
	@echo "make bench-snapshots make bench's snapshot tables alone: sizes, snapshot and restore against a step"
	@echo "make count-snapshots snapshot and restore of the 3000-ball basin against a step, in instructions"
	@echo "                    counted by valgrind; table into $(ORG)"
	@echo "make fuzz-snapshots make fuzz's damaged snapshots alone (SEED=1 COUNT=2000); figures into $(ORG)"
	@echo "make bench-peers    the basin here (1 and 2 workers), in Debian's Bullet and in ODE, one run; with"
	@echo "                    BOX3D_SRC=dir (a checkout of erincatto/box3d) in Box3D too, 1 and 2 workers"
	@echo "make bench-against  this engine against the commits REVS='ce415a5 d9c8f94' in ROUNDS=5 rounds of"
	@echo "                    alternating processes; table into $(ORG)"
	@echo "make count-against  the same engines' instructions a step, counted by valgrind; table into $(ORG)"
	@echo "make bench-joint-grid BOX3D_SRC=dir  Box3D's joint grid here and in Box3D built from dir, in"
	@echo "                    ROUNDS=5 rounds of alternating processes; table into $(ORG)"
	@echo "make bench-pyramid BOX3D_SRC=dir  Box3D's large pyramid (5050 cubes) here and in Box3D built"
	@echo "                    from dir, ROUNDS=5 rounds of alternating processes; table into $(ORG)"
	@echo "make count-features the feature table's scenes as instructions a step, by valgrind; table into $(ORG)"
	@echo "make count-pyramid  a pyramid of 40 cubes at its base, instructions a step, by valgrind; table into $(ORG)"
	@echo "make report         stiff and extreme cases, and error against run time; tables into $(ORG),"
	@echo "                    diagrams into report/wp-*.svg"
	@echo "make report-peers   every scene of the error-against-run-time sweep here, in Debian's Bullet and"
	@echo "                    in ODE (and Box3D with BOX3D_SRC=dir, a checkout of its source), one run;"
	@echo "                    diagrams into report/wp-peers-*.svg, the table into $(ORG)"
	@echo "make heaps          heaps of 1000 balls to the body budget spawned at one point; table into $(ORG)"
	@echo "make mutate         run the claims against COUNT=150 mutants of the engine (SEED=1, ANCHOR=ID"
	@echo "                    for one section, PART='solver|hash' for the drawn mutants of some parts,"
	@echo "                    LIST=1 to print the draw); the score table and the survivors into $(ORG)"
	@echo "make mutate-splice  the last full run's tables into $(ORG), with the page's reasons for survivors"
	@echo "make prose-count    the page's prose words by kind, its sections, blocks and longest definitions;"
	@echo "                    into $(ORG)"
	@echo "make html           write physics.html: the page, its code coloured, with an index of the interface,"
	@echo "                    and report/notebook.html, the history of the measurements"
	@echo "make view SCENE=basin  record a scene (basin, pile, fountain, lava, player, ...) and write"
	@echo "                    report/view-SCENE.html, a 3D viewer of the run for any browser"
	@echo "make view FILE=f.lisp  record the world f.lisp's last form returns (STEPS=240 EVERY=2,"
	@echo "                    BOUNDS='x0 y0 z0 x1 y1 z1' the terrain drawn) into report/view-f.html"
	@echo "make pictures       draw each scene at a few moments: report/scene-*.svg, shown by the page"
	@echo "make fuzz           random operation sequences (SEED=1 COUNT=1200 LENGTH=150), then random squeezes"
	@echo "                    (SCENES=40 STEPS=300), then damaged snapshots of the scenes; figures into $(ORG)"
	@echo "make soak           a churning world for MINUTES=5 minutes; its heap curve into $(ORG)"
	@echo "make clean          remove editor backups and this repository's compiled files"

setup:
	@tools/setup "$(SBCL)" "$(EMACS)"

tangle:
	@tools/tangle-page "$(EMACS)" $(ORG)

check-tangle:
	@tools/check-tangle "$(EMACS)" $(ORG) $(OUT)

check-anchors:
	@$(LISP) --load tools/check-anchors.lisp

# what the compiler prints goes to report/compile.log (tools/boot.lisp), what the claims print to
# report/claims.log (tests/run.lisp); a run of make test starts the compile log afresh
test: setup fresh-compile-log check-tangle check-anchors physics.html
	@ANCHOR="$(ANCHOR)" LUV_HEAP="$(HEAP)" tools/run-tests "$(SBCL)" "$(EMACS)"

fresh-compile-log:
	@mkdir -p report && rm -f report/compile.log

editor-test: setup
	@LUV_HEAP="$(HEAP)" tools/editor-test "$(SBCL)" "$(EMACS)"

demo: setup tangle
	@SCENE="$(SCENE)" SAVE="$(SAVE)" $(LISP) --load tools/demo.lisp

# The engine system's load (#W0RKSH): fresh SBCLs, an empty ASDF cache for the compile.
load-time: setup tangle
	@mkdir -p report
	@$(LISP) --load tools/load-time.lisp | tee report/load-time.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp engine-load-time report/load-time.org

bench: setup tangle
	@mkdir -p report
	@$(LISP) --load tools/bench.lisp | tee report/bench.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp bench-basin report/bench.org
	@BENCH=run-scene-benchmark $(LISP) --load tools/bench.lisp | tee report/bench-scenes.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp bench-scenes report/bench-scenes.org
	@BENCH=run-sleeping-scale-benchmark $(LISP) --load tools/bench.lisp | tee report/bench-sleeping.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp bench-sleeping report/bench-sleeping.org
	@BENCH=run-query-benchmark $(LISP) --load tools/bench.lisp | tee report/bench-queries.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp bench-queries report/bench-queries.org
	@BENCH=run-feature-benchmark $(LISP) --load tools/bench.lisp | tee report/bench-features.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp bench-features report/bench-features.org
	@BENCH=run-snapshot-benchmark $(LISP) --load tools/bench.lisp | tee report/bench-snapshots.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp bench-snapshots report/bench-snapshots.org
	@$(MAKE) --no-print-directory bench-workers

# an 8-step rollback at 1000 balls (#SNCOST): cheap to run again alone, at a quiet moment
bench-rollback: setup tangle
	@mkdir -p report
	@BENCH=run-rollback-benchmark $(LISP) --load tools/bench.lisp | tee report/bench-rollback.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp bench-rollback report/bench-rollback.org

# make bench's snapshot tables alone (#SNCOST), and the same measure in instructions, load-proof
bench-snapshots: setup tangle
	@mkdir -p report
	@BENCH=run-snapshot-benchmark $(LISP) --load tools/bench.lisp | tee report/bench-snapshots.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp bench-snapshots report/bench-snapshots.org

count-snapshots: setup tangle
	@mkdir -p report
	@command -v valgrind >/dev/null 2>&1 || { echo "count-snapshots: valgrind is not installed (make setup as root installs it)" >&2; exit 1; }
	@rm -f report/count-snapshots-failed
	@{ BENCH=run-count-snapshots $(LISP) --load tools/bench.lisp || touch report/count-snapshots-failed; } | tee report/count-snapshots.org
	@test ! -e report/count-snapshots-failed
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp count-snapshots report/count-snapshots.org

# make fuzz's damaged snapshots alone (#SNFUZZ)
fuzz-snapshots: setup tangle
	@mkdir -p report
	@rm -f report/fuzz-failed
	@{ FUZZ=snapshot SEED="$(SEED)" $(if $(filter command line environment,$(origin COUNT)),COUNT="$(COUNT)") nice $(LISP) --load tools/fuzz.lisp || touch report/fuzz-failed; } | tee report/snapshot-fuzz.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp snapshot-fuzz report/snapshot-fuzz.org
	@test ! -e report/fuzz-failed

# the basin with one worker and with two, interleaved (#B3NCHW): cheap to run again alone
bench-workers: setup tangle
	@mkdir -p report
	@BENCH=run-worker-benchmark $(LISP) --load tools/bench.lisp | tee report/bench-workers.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp bench-workers report/bench-workers.org

# Bullet's side is tools/peers/bullet-basin.cpp, ODE's tools/peers/ode-basin.cpp, both built
# without -march=native like Debian's Bullet and ODE; with BOX3D_SRC=dir (a checkout of
# erincatto/box3d), Box3D's is tools/peers/box3d-basin.cpp, built here from it (#B3NCHW).
bench-peers: setup tangle
	@tools/peers/setup libbullet-dev libode-dev g++ pkg-config
	@mkdir -p report/peers
	@$(CXX) -O2 -o report/peers/bullet-basin tools/peers/bullet-basin.cpp $$(pkg-config --cflags --libs bullet)
	@$(CXX) -O2 -o report/peers/ode-basin tools/peers/ode-basin.cpp $$(pkg-config --cflags --libs ode)
	@rm -f report/peers/box3d-basin
	@if [ -n "$(BOX3D_SRC)" ]; then \
	  mkdir -p report/peers/box3d-obj && \
	  for f in $(BOX3D_SRC)/src/*.c; do \
	    o=report/peers/box3d-obj/$$(basename $$f .c).o; \
	    [ -e $$o -a $$o -nt $$f ] || $(CC) -O2 -DNDEBUG -std=gnu17 -I$(BOX3D_SRC)/include -I$(BOX3D_SRC)/src -c $$f -o $$o || exit 1; \
	  done && \
	  $(CXX) -O2 -I$(BOX3D_SRC)/include -o report/peers/box3d-basin tools/peers/box3d-basin.cpp report/peers/box3d-obj/*.o -lpthread -lm; \
	fi
	@rm -f report/peers/failed
	@{ BULLET_BASIN=report/peers/bullet-basin ODE_BASIN=report/peers/ode-basin BOX3D_BASIN=$(if $(BOX3D_SRC),report/peers/box3d-basin,) $(LISP) --load tools/peers/bench-peers.lisp || touch report/peers/failed; } | tee report/peers.org
	@test ! -e report/peers/failed
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp bench-peers report/peers.org

# This page's engine against the engines of earlier commits, in alternating processes (#B3NCH5).
REVS ?= ce415a5 d9c8f94
ROUNDS ?= 5
bench-against: setup tangle
	@mkdir -p report
	@REVS="$(REVS)" ROUNDS="$(ROUNDS)" BENCH=run-against-benchmark $(LISP) --load tools/bench.lisp | tee report/bench-against.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp bench-against report/bench-against.org

# Instructions a step, counted by valgrind's cachegrind, which the machine's load does not move:
# count-against, the engines of REVS against this one (#B3NCH5); count-features, the feature
# table's scenes general and specialised (#FBNCH9); count-pyramid, Box3D's pyramid smaller (#PYR4MD).
count-against count-features count-pyramid: count-%: setup tangle
	@mkdir -p report
	@command -v valgrind >/dev/null 2>&1 || { echo "count-$*: valgrind is not installed (make setup as root installs it)" >&2; exit 1; }
	@rm -f report/count-$*-failed
	@{ REVS="$(REVS)" BENCH=run-count-$* $(LISP) --load tools/bench.lisp || touch report/count-$*-failed; } | tee report/count-$*.org
	@test ! -e report/count-$*-failed
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp count-$* report/count-$*.org

# Box3D's joint grid here and in Box3D (#J0GR1D), alternating processes: BOX3D_SRC=dir, a checkout
# of github.com/erincatto/box3d, is built here for the measurement only.
bench-joint-grid: setup tangle
	@test -n "$(BOX3D_SRC)" || { echo "bench-joint-grid: BOX3D_SRC=dir, a checkout of erincatto/box3d, is needed" >&2; exit 1; }
	@mkdir -p report/peers/box3d-obj
	@for f in $(BOX3D_SRC)/src/*.c; do \
	  o=report/peers/box3d-obj/$$(basename $$f .c).o; \
	  [ -e $$o -a $$o -nt $$f ] || $(CC) -O2 -DNDEBUG -std=gnu17 -I$(BOX3D_SRC)/include -I$(BOX3D_SRC)/src -c $$f -o $$o || exit 1; \
	done
	@$(CC) -O2 -std=gnu17 -I$(BOX3D_SRC)/include -o report/peers/box3d-joint-grid tools/peers/box3d-joint-grid.c report/peers/box3d-obj/*.o -lpthread -lm
	@ROUNDS="$(ROUNDS)" BENCH=run-joint-grid-benchmark $(LISP) --load tools/bench.lisp | tee report/bench-joint-grid.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp bench-joint-grid report/bench-joint-grid.org

# Box3D's large pyramid here and in Box3D (#PYR4MD), alternating processes: BOX3D_SRC=dir, a
# checkout of github.com/erincatto/box3d, is built here for the measurement only.
bench-pyramid: setup tangle
	@test -n "$(BOX3D_SRC)" || { echo "bench-pyramid: BOX3D_SRC=dir, a checkout of erincatto/box3d, is needed" >&2; exit 1; }
	@mkdir -p report/peers/box3d-obj
	@for f in $(BOX3D_SRC)/src/*.c; do \
	  o=report/peers/box3d-obj/$$(basename $$f .c).o; \
	  [ -e $$o -a $$o -nt $$f ] || $(CC) -O2 -DNDEBUG -std=gnu17 -I$(BOX3D_SRC)/include -I$(BOX3D_SRC)/src -c $$f -o $$o || exit 1; \
	done
	@$(CC) -O2 -std=gnu17 -I$(BOX3D_SRC)/include -o report/peers/box3d-large-pyramid tools/peers/box3d-large-pyramid.c report/peers/box3d-obj/*.o -lpthread -lm
	@ROUNDS="$(ROUNDS)" BENCH=run-pyramid-benchmark $(LISP) --load tools/bench.lisp | tee report/bench-pyramid.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp bench-pyramid report/bench-pyramid.org

# The diagrams report/wp-*.svg are kept in git: the page links to them.
report: setup tangle
	@mkdir -p report
	@REPORT=stability $(LISP) --load tools/report.lisp | tee report/stability.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp stability-table report/stability.org
	@REPORT=accuracy $(LISP) --load tools/report.lisp
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp work-precision-best report/work-precision-best.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp work-precision-table report/work-precision.org

# The sweep's scenes in this engine, Bullet and ODE (#P33R5X): the page writes the scenes as data
# into report/peers/scenes.txt, tools/peers/bullet-scenes.cpp and ode-scenes.cpp run them.
# BOX3D_SRC=dir, a checkout of github.com/erincatto/box3d, adds Box3D, built here from it.
BOX3D_SRC ?=
report-peers: setup tangle
	@tools/peers/setup libbullet-dev libode-dev g++ pkg-config
	@mkdir -p report/peers
	@rm -f report/peers/box3d-scenes
	@if [ -n "$(BOX3D_SRC)" ]; then \
	  mkdir -p report/peers/box3d-obj && \
	  for f in $(BOX3D_SRC)/src/*.c; do \
	    $(CC) -O2 -DNDEBUG -std=gnu17 -I$(BOX3D_SRC)/include -I$(BOX3D_SRC)/src -c $$f -o report/peers/box3d-obj/$$(basename $$f .c).o || exit 1; \
	  done && \
	  $(CXX) -O2 -I$(BOX3D_SRC)/include -o report/peers/box3d-scenes tools/peers/box3d-scenes.cpp report/peers/box3d-obj/*.o -lpthread -lm; \
	fi
	@$(CXX) -O2 -o report/peers/bullet-scenes tools/peers/bullet-scenes.cpp $$(pkg-config --cflags --libs bullet)
	@$(CXX) -O2 -o report/peers/ode-scenes tools/peers/ode-scenes.cpp $$(pkg-config --cflags --libs ode)
	@rm -f report/peers/failed
	@{ REPORT=peers $(LISP) --load tools/report.lisp || touch report/peers/failed; } | tee report/peers.log
	@test ! -e report/peers/failed
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp peer-table report/peers-table.org

# Heaps spawned at one point, 1000 balls to the body budget: memory per body and speeds (#X7R3M5).
heaps: setup tangle
	@mkdir -p report
	@rm -f report/heaps-failed
	@{ REPORT=heaps nice $(LISP) --load tools/report.lisp || touch report/heaps-failed; } | tee report/heaps.org
	@test ! -e report/heaps-failed
	@$(SBCL) --script tools/splice.lisp heap-sizes report/heaps.org

# Mutants are sampled from the tangled files as they are; the tables are spliced only after a
# run over every section and every part (no ANCHOR, PART, MATCH or LIST).
mutate: setup tangle
	@mkdir -p report
	@SEED="$(SEED)" COUNT="$(COUNT)" ANCHOR="$(ANCHOR)" PART="$(PART)" LIST="$(LIST)" nice $(SBCL) --dynamic-space-size $(HEAP) --disable-ldb --lose-on-corruption --noinform --non-interactive --no-sysinit --no-userinit --load tools/mutate.lisp | tee report/mutate.log
	@if [ -z "$(ANCHOR)$(PART)$(LIST)$$MATCH" ]; then $(MAKE) --no-print-directory mutate-splice; fi

# The last full run's tables, from its log, into the page; the survivors' reasons, and which
# survivors are equivalent, are read from the page as it is.
mutate-splice:
	@MUTATE_FROM_LOG=report/mutate.log $(LISP) --load tools/mutate.lisp
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp mutate-score report/mutate-score.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp mutate-survivors report/mutate-survivors.org

# The page's prose by kind (explanation, claims, measurements, mutant records), its sections,
# engine blocks and longest definitions; the rule is in tools/prose-count.lisp and on the page (#LW3YHU).
prose-count:
	@mkdir -p report
	@$(SBCL) --script tools/prose-count.lisp | tee report/prose-count.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp prose-count report/prose-count.org

# The page as HTML: the index of the exported symbols comes from the loaded image
# (report/api-index.org), then Org's export in batch Emacs writes physics.html, again only when
# the page, the tangled files or these tools changed.  It uses the tangled files as they are:
# after editing the page, make tangle first.
html: physics.html

physics.html: $(ORG) $(OUT) luv-physics.asd tools/export.el tools/api-index.lisp report/notebook.org | setup
	@mkdir -p report
	@$(LISP) --load tools/api-index.lisp
	@$(EMACS) -Q --batch -l tools/export.el $(ORG) physics.html
	@$(EMACS) -Q --batch -l tools/export.el report/notebook.org $(CURDIR)/report/notebook.html

SCENE ?= basin
EVERY ?= 2
view: setup
	@SCENE="$(SCENE)" EVERY="$(EVERY)" FILE="$(FILE)" STEPS="$(STEPS)" BOUNDS="$(BOUNDS)" $(LISP) --load tools/view.lisp

# The pictures report/scene-*.svg are kept in git: the page shows them.
pictures: setup
	@$(LISP) --load tools/pictures.lisp

# Long campaigns, outside make test: the random operation sequences and the soak (#M9W5P7).
fuzz: setup tangle
	@mkdir -p report
	@rm -f report/fuzz-failed
	@{ SEED="$(SEED)" COUNT="$(FUZZ_COUNT)" LENGTH="$(LENGTH)" nice $(LISP) --load tools/fuzz.lisp || touch report/fuzz-failed; } | tee report/fuzz.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp fuzz-campaign report/fuzz.org
	@{ FUZZ=squeeze SEED="$(SEED)" SCENES="$(SCENES)" STEPS="$(STEPS)" nice $(LISP) --load tools/fuzz.lisp || touch report/fuzz-failed; } | tee report/squeeze.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp squeeze-campaign report/squeeze.org
	@{ FUZZ=snapshot SEED="$(SEED)" nice $(LISP) --load tools/fuzz.lisp || touch report/fuzz-failed; } | tee report/snapshot-fuzz.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp snapshot-fuzz report/snapshot-fuzz.org
	@test ! -e report/fuzz-failed

soak: setup tangle
	@mkdir -p report
	@MINUTES="$(MINUTES)" nice $(LISP) --load tools/soak.lisp | tee report/soak.org
	@$(SBCL) --dynamic-space-size $(HEAP) --script tools/splice.lisp soak-heap report/soak.org

clean:
	find . -name .git -prune -o \( -name '*~' -o -name '#*#' -o -name '.#*' -o -name '*.fasl' \) -print0 | xargs -0 rm -f
	find report -type f ! -name 'wp-*.svg' ! -name 'scene-*.svg' ! -name 'screenshot-*.png' ! -name 'notebook.org' -delete 2>/dev/null || true
	rm -f physics.html physics-script-check.html
	@$(LISP) --eval '(require :asdf)' \
	  --eval '(let ((cache (asdf:apply-output-translations (truename "./")))) (format t "rm -rf ~A~%" cache) (uiop:delete-directory-tree cache :validate t :if-does-not-exist :ignore))'
