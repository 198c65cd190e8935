;;;; tools/pyramid-one.lisp -- one process of make bench-pyramid (physics.org, #PYR4MD): load the
;;;; engine of the tree ROOT and print, for each kernel family, one line
;;;;   pyramid FAMILY MS TOP-Y TOP-X
;;;; this thread's CPU time per step, in ms, over STEPS steps of Box3D's large pyramid of BASE
;;;; cubes at its base (large-pyramid-world), and the top cube's centre at the end.  With FAMILIES
;;;; the word profile, it runs the scalar family under sb-sprof instead and prints one line
;;;;   profile FUNCTION SHARE
;;;; for each function holding at least 1 % of the samples by itself.  With FAMILIES the word hash-
;;;; and a family (hash-scalar), make count-pyramid's process under valgrind, it steps that family's
;;;; pyramid STEPS times and prints one line
;;;;   pyramid FAMILY HASH
;;;; with the world's state hash.
;;;;
;;;; Usage: sbcl --script tools/pyramid-one.lisp ROOT/ FAMILIES BASE STEPS   (FAMILIES as scalar,avx2)

(load (merge-pathnames "one-process.lisp" *load-truename*))

(defvar *pyramid-arguments* (one-process-arguments "pyramid-one" "ROOT/ FAMILIES BASE STEPS" 4))

(defun pyramid-cpu-ns ()
  "This thread's CPU time in nanoseconds."
  (multiple-value-bind (seconds nanoseconds) (sb-unix::clock-gettime sb-unix:clock-thread-cputime-id)
    (+ (* seconds 1000000000) nanoseconds)))

(defun pyramid-profile (base steps)
  "Print the share of the samples each function holds by itself over STEPS steps of the scalar
family's pyramid of BASE, after two steps to settle the buffers."
  (require :sb-sprof)
  (let ((world (funcall (find-symbol "LARGE-PYRAMID-WORLD" :luv-physics) base :kernels :scalar))
        (step (find-symbol "STEP-PHYSICS-WORLD" :luv-physics)))
    (dotimes (i 2) (funcall step world))
    (funcall (find-symbol "START-PROFILING" "SB-SPROF") :max-samples 100000 :mode :cpu :sample-interval 0.001
             :threads (list sb-thread:*current-thread*))
    (dotimes (i steps) (funcall step world))
    (funcall (find-symbol "STOP-PROFILING" "SB-SPROF"))
    (let ((text (with-output-to-string (*standard-output*)
                  (funcall (find-symbol "REPORT" "SB-SPROF") :type :flat :max 40))))
      ;; rows: Nr Count % Count % Count % Calls Function
      (dolist (line (uiop:split-string text :separator '(#\Newline)))
        (let ((words (remove "" (uiop:split-string line) :test #'string=)))
          (when (and (>= (length words) 9) (every #'digit-char-p (first words)))
            (let ((share (let ((*read-default-float-format* 'double-float)) (read-from-string (third words)))))
              (when (>= share 1)
                (format t "~&profile ~A ~,1F~%" (format nil "~{~A~^ ~}" (nthcdr 8 words)) share)))))))))

(destructuring-bind (root families base steps) *pyramid-arguments*
  (declare (ignore root))
  (let ((base (parse-integer base)) (steps (parse-integer steps)))
    (cond
      ((string= families "profile") (pyramid-profile base steps))
      ((and (> (length families) 5) (string= (subseq families 0 5) "hash-"))
       (let ((family (intern (string-upcase (subseq families 5)) :keyword)))
         (let ((world (funcall (find-symbol "LARGE-PYRAMID-WORLD" :luv-physics) base :kernels family)))
           (dotimes (i steps) (funcall (find-symbol "STEP-PHYSICS-WORLD" :luv-physics) world))
           (format t "~&pyramid ~(~A~) ~D~%" family
                   (funcall (find-symbol "PHYSICS-WORLD-STATE-HASH" :luv-physics) world))
           (finish-output))))
      (t
        (dolist (name (uiop:split-string families :separator ","))
          (let ((family (intern (string-upcase name) :keyword)))
            (multiple-value-bind (world top) (funcall (find-symbol "LARGE-PYRAMID-WORLD" :luv-physics) base :kernels family)
              (let ((start (pyramid-cpu-ns)))
                (dotimes (i steps) (funcall (find-symbol "STEP-PHYSICS-WORLD" :luv-physics) world))
                (multiple-value-bind (x y) (funcall (find-symbol "PHYSICS-BODY-POSITION" :luv-physics) world top)
                  (format t "~&pyramid ~(~A~) ~,4F ~,4F ~,4F~%" family (/ (- (pyramid-cpu-ns) start) 1d6 steps) y x))
                (finish-output)))))))))
