;;;; tools/against-one.lisp -- one process of make bench-against (physics.org, #B3NCH5): load the
;;;; engine of the tree ROOT and print, for each kernel family, one line
;;;;   against FAMILY MEDIAN-MS HASH
;;;; the median CPU time of this thread per step of the basin of BALLS awake balls over steps
;;;; FROM..TO, and the state hash after TO steps.  BALLS 0 only loads the engine (compiling it
;;;; into the ASDF cache when needed) and prints nothing.
;;;;
;;;; Usage: sbcl --script tools/against-one.lisp ROOT/ FAMILIES BALLS FROM TO
;;;; (FAMILIES as scalar,sse,avx2).  It uses only what every tree of the engine since the
;;;; basin benchmark has: tools/boot.lisp, make-basin-world, step-physics-world, median and
;;;; physics-world-state-hash, so that one script measures old and new trees alike.

(load (merge-pathnames "one-process.lisp" *load-truename*))

(defvar *against-arguments* (one-process-arguments "against-one" "ROOT/ FAMILIES BALLS FROM TO" 5))

(defun against-cpu-ns ()
  "This thread's CPU time in nanoseconds."
  (multiple-value-bind (seconds nanoseconds) (sb-unix::clock-gettime sb-unix:clock-thread-cputime-id)
    (+ (* seconds 1000000000) nanoseconds)))

(destructuring-bind (root families balls from to) *against-arguments*
  (declare (ignore root))
  (let ((balls (parse-integer balls)) (from (parse-integer from)) (to (parse-integer to)))
    (when (plusp balls)
      (dolist (name (uiop:split-string families :separator ","))
        (let* ((family (intern (string-upcase name) :keyword))
               (world (funcall (find-symbol "MAKE-BASIN-WORLD" :luv-physics) balls :kernels family))
               (step (find-symbol "STEP-PHYSICS-WORLD" :luv-physics))
               (times '()))
          (dotimes (i to)
            (let ((start (against-cpu-ns)))
              (funcall step world)
              (when (>= i from) (push (/ (- (against-cpu-ns) start) 1d6) times))))
          (format t "~&against ~(~A~) ~,4F ~D~%" family (funcall (find-symbol "MEDIAN" :luv-physics) times)
                  (funcall (find-symbol "PHYSICS-WORLD-STATE-HASH" :luv-physics) world))
          (finish-output))))))
