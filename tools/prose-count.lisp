;;;; tools/prose-count.lisp -- physics.org's prose by kind, its sections and blocks, the longest definitions.
;;;; Usage: sbcl --script tools/prose-count.lisp [PAGE]      (run from the repository; PAGE is physics.org)
;;;; 'make prose-count' runs it and splices its output into the page's block '#+name: prose-count'.
;;;; PROSE_COUNT_DUMP=FILE also writes every paragraph with its kind to FILE, to check the rule.
;;;;
;;;; What is counted.  Words are runs of characters between blanks.  The lines of the page are
;;;; split first into what is not prose: the lines of #+begin_src and #+begin_example blocks
;;;; (code and results), keyword lines (#+name:, #+caption:, #+TOC: ...), :PROPERTIES: drawers;
;;;; table lines (starting with |) are counted apart as tables, heading lines apart as headings.
;;;; What remains is prose, cut into paragraphs at blank lines and at everything above.  Each
;;;; paragraph has one kind, the first of these that applies:
;;;;
;;;;  1. mutant record: it lies inside a :MUTANTS: drawer, or starts "Equivalent mutant ~" or
;;;;     "Surviving mutant ~" (the records tools/mutate.lisp reads back);
;;;;  2. claim: it starts with the word "Claim" (the paragraph stating a claim, which
;;;;     make check-anchors requires directly before each test block);
;;;;  3. measurement: it reports figures of a run: it names a commit (a word of 7 to 40
;;;;     lowercase hex digits with at least one letter and one digit), or has a number followed
;;;;     by a unit of time or of instructions (ns, us, µs, ms, "s a step", "s per", seconds,
;;;;     minutes, instructions, "million(s) of instructions"), or a machine's "load" followed
;;;;     by a number, or the word "measured" or "timed";
;;;;  4. explanation: every other paragraph.
;;;; The mutant records themselves live in tests/mutant-records.org, off the page; the report
;;;; counts them there on a line of their own.
;;;;
;;;; Sections are the headings' spans (a heading to the next heading of any level); engine
;;;; blocks are the #+begin_src blocks that tangle into tangled/physics.lisp or
;;;; tangled/physics-simd.lisp (by their own :tangle, else the nearest heading's
;;;; header-args:lisp+, else the page's :tangle no); their length is the lines between
;;;; #+begin_src and #+end_src.  The longest definitions are the top-level forms of the two
;;;; tangled engine files, by lines, with the deepest nesting of parentheses in them (the form's
;;;; own parenthesis is depth 1; strings, comments and character literals are skipped), and
;;;; then every one of them over the page's bound: 120 lines, or deeper than 16 parentheses.

(defun lines-of (path)
  (with-open-file (s path :external-format :utf-8)
    (coerce (loop for line = (read-line s nil) while line collect line) 'vector)))

(defun trim (s) (string-trim '(#\Space #\Tab) s))

(defun starts-with (prefix s)
  (and (<= (length prefix) (length s)) (string= prefix s :end2 (length prefix))))

(defun starts-with-ci (prefix s)
  (and (<= (length prefix) (length s)) (string-equal prefix s :end2 (length prefix))))

(defun blank-p (s) (zerop (length (trim s))))

(defun heading-level (line)
  "The number of stars of a heading line, or NIL."
  (let ((stars (or (position #\* line :test-not #'char=) (length line))))
    (and (plusp stars) (< stars (length line)) (char= #\Space (char line stars)) stars)))

(defun words (s)
  (let ((count 0) (in nil))
    (loop for c across s
          do (if (member c '(#\Space #\Tab #\Newline))
                 (setf in nil)
                 (unless in (setf in t) (incf count))))
    count))

(defun heading-words (line)
  "The words of a heading, without its stars and its :tags:."
  (let* ((text (trim (string-left-trim "*" line)))
         (end (length text)))
    (when (and (plusp end) (char= (char text (1- end)) #\:))
      (let ((at (position #\Space text :from-end t)))
        (when (and at (char= (char text (1+ at)) #\:)) (setf text (subseq text 0 at)))))
    (words text)))

(defun median (numbers)
  (if (null numbers) 0
      (let* ((v (sort (coerce numbers 'vector) #'<)) (n (length v)))
        (if (oddp n) (aref v (floor n 2)) (/ (+ (aref v (1- (floor n 2))) (aref v (floor n 2))) 2)))))

(defun header-tangle (header)
  "The file a #+begin_src line's :tangle names, or NIL if it names none."
  (let ((at (search ":tangle " header)))
    (and at (let* ((start (+ at 8)) (end (or (position #\Space header :start start) (length header))))
              (subseq header start end)))))

;;; The rule's tests on a paragraph's text

(defun hex-word-p (w)
  (and (<= 7 (length w) 40)
       (every (lambda (c) (or (char<= #\0 c #\9) (char<= #\a c #\f))) w)
       (some #'digit-char-p w) (some #'alpha-char-p w)))

(defun tokens (text)
  "TEXT cut at every character that is not a letter, a digit, a point or µ."
  (let ((out '()) (start nil))
    (loop for i from 0 to (length text)
          for c = (if (< i (length text)) (char text i) #\Space)
          do (if (or (alphanumericp c) (char= c #\.) (char= c #\µ))
                 (unless start (setf start i))
                 (when start (push (string-right-trim "." (subseq text start i)) out) (setf start nil))))
    (remove "" (nreverse out) :test #'string=)))

(defun number-word-p (w)
  (and (plusp (length w)) (digit-char-p (char w 0)) (every (lambda (c) (or (digit-char-p c) (char= c #\.))) w)))

(defparameter *units* '("ns" "us" "µs" "ms" "seconds" "minutes" "instructions"))

(defun measurement-p (text)
  (let ((ts (tokens text)))
    (or (some #'hex-word-p ts)
        (loop for (a b c) on ts
              thereis (or (and (number-word-p a) b
                               (or (member b *units* :test #'string-equal)
                                   (and (string= b "s") c (member c '("a" "per") :test #'string-equal))
                                   (and (string-equal b "million") c (string-equal c "instructions"))
                                   (and (string-equal b "millions") c (string-equal c "of"))))
                          (and (string-equal a "load") b (number-word-p b))))
        (some (lambda (w) (member w '("measured" "timed") :test #'string-equal)) ts))))

;;; The page

(defstruct para kind (words 0) start (text ""))

(defun survey (lines)
  "Walk LINES: return the paragraphs, the table and heading words, the sections' lengths by level
and the engine blocks' lengths."
  (let ((paras '()) (table-words 0) (heading-words 0) (headings '()) (engine-blocks '())
        (tangle "no") (heading-tangle '()) ; (level . tangle) of the open headings
        (current nil) (drawer nil)
        (n (length lines)) (i 0))
    (labels ((close-para ()
               (when current
                 (let* ((text (para-text current))
                        (kind (cond ((eq (para-kind current) :mutant) :mutant)
                                    ((or (starts-with "Equivalent mutant ~" text)
                                         (starts-with "Surviving mutant ~" text)) :mutant)
                                    ((starts-with "Claim" text) :claim)
                                    ((measurement-p text) :measurement)
                                    (t :explanation))))
                   (setf (para-kind current) kind (para-words current) (words text))
                   (push current paras)
                   (setf current nil))))
             (block-tangle (header)
               (or (header-tangle header)
                   (or (cdr (first heading-tangle)) tangle))))
      (loop while (< i n)
            do (let* ((line (aref lines i)) (tl (trim line)))
                 (cond
                   ((heading-level line)
                    (close-para)
                    (let ((level (heading-level line)))
                      (push (list level i) headings)
                      (setf heading-tangle (remove-if (lambda (e) (>= (car e) level)) heading-tangle))
                      (push (cons level (cdr (first heading-tangle))) heading-tangle))
                    (incf heading-words (heading-words line)))
                   ((starts-with-ci "#+PROPERTY: header-args:lisp " tl)
                    (let ((tg (header-tangle tl))) (when tg (setf tangle tg))))
                   ((starts-with-ci "#+begin_src" tl)
                    (close-para)
                    (let ((end (or (position-if (lambda (l) (starts-with-ci "#+end_src" (trim l))) lines :start (1+ i))
                                   n))
                          (file (block-tangle tl)))
                      (when (member file '("tangled/physics.lisp" "tangled/physics-simd.lisp") :test #'string=)
                        (push (- end i 1) engine-blocks))
                      (setf i end)))
                   ((starts-with-ci "#+begin_example" tl)
                    (close-para)
                    (setf i (or (position-if (lambda (l) (starts-with-ci "#+end_example" (trim l))) lines :start (1+ i))
                                n)))
                   ((string-equal tl ":PROPERTIES:")
                    (close-para) (setf drawer :properties))
                   ((string-equal tl ":MUTANTS:")
                    (close-para) (setf drawer :mutants))
                   ((string-equal tl ":END:")
                    (close-para) (setf drawer nil))
                   ((eq drawer :properties)
                    (let ((tg (and (starts-with ":header-args:lisp" tl) (header-tangle tl))))
                      (when tg (setf (cdr (first heading-tangle)) tg))))
                   ((starts-with "#+" tl) (close-para))
                   ((starts-with "|" tl)
                    (close-para)
                    (unless (starts-with "|-" tl)
                      (incf table-words (words (substitute #\Space #\| tl)))))
                   ((blank-p line) (close-para))
                   (t
                    (if current
                        (setf (para-text current) (concatenate 'string (para-text current) " " tl))
                        (setf current (make-para :kind (and (eq drawer :mutants) :mutant) :start (1+ i) :text tl))))))
               (incf i))
      (close-para))
    (let* ((starts (sort (mapcar #'second headings) #'<))
           (lengths (loop for (a b) on starts collect (- (or b n) a))))
      (values (nreverse paras) table-words heading-words
              (reverse headings) lengths (nreverse engine-blocks)))))

;;; The tangled files' top-level forms

(defun forms-of (path)
  "Each top-level form of the Lisp file PATH as (name lines max-depth start-line)."
  (let* ((text (with-open-file (s path :external-format :utf-8)
                 (let ((out (make-string (file-length s))))
                   (subseq out 0 (read-sequence out s)))))
         (n (length text)) (line 1) (depth 0) (max 0) (start nil) (start-line 0) (forms '()))
    (flet ((name-at (from)
             ;; the operator and the word after it
             (let* ((a (position-if-not (lambda (c) (member c '(#\( #\Space #\Newline))) text :start from))
                    (b (position-if (lambda (c) (member c '(#\Space #\Newline #\( #\)))) text :start a))
                    (c (position-if-not (lambda (c) (member c '(#\Space #\Newline #\())) text :start b))
                    (d (position-if (lambda (c) (member c '(#\Space #\Newline #\( #\)))) text :start c)))
               (format nil "~A ~A" (subseq text a b) (subseq text c d)))))
      (loop with i = 0
            while (< i n)
            do (let ((c (char text i)))
                 (case c
                   (#\Newline (incf line))
                   (#\; (loop while (and (< i n) (char/= (char text i) #\Newline)) do (incf i))
                    (decf i))
                   (#\" (incf i)
                    (loop while (and (< i n) (char/= (char text i) #\"))
                          do (when (char= (char text i) #\\) (incf i))
                             (when (and (< i n) (char= (char text i) #\Newline)) (incf line))
                             (incf i)))
                   (#\# (cond ((and (< (1+ i) n) (char= (char text (1+ i)) #\\)) (incf i 2))
                              ((and (< (1+ i) n) (char= (char text (1+ i)) #\|))
                               (let ((end (search "|#" text :start2 (+ i 2))))
                                 (incf line (count #\Newline text :start i :end end))
                                 (setf i (1+ end))))))
                   (#\( (when (zerop depth) (setf start i start-line line max 0))
                    (incf depth) (setf max (max max depth)))
                   (#\) (decf depth)
                    (when (zerop depth)
                      (push (list (name-at start) (1+ (- line start-line)) max start-line) forms)))))
               (incf i)))
    forms))

;;; The report

(defparameter *records-file* "tests/mutant-records.org"
  "The mutant records, which tools/mutate.lisp reads; counted apart from the page.")

(let* ((page (or (second sb-ext:*posix-argv*) "physics.org"))
       (lines (lines-of page)))
  (multiple-value-bind (paras table-words heading-words headings lengths blocks) (survey lines)
    (let* ((kinds '((:explanation "explanation") (:claim "claims") (:measurement "measurement")
                    (:mutant "mutant records")))
           (sums (mapcar (lambda (k) (reduce #'+ (remove (car k) paras :key #'para-kind :test-not #'eq)
                                             :key #'para-words))
                         kinds))
           (counts (mapcar (lambda (k) (count (car k) paras :key #'para-kind)) kinds))
           (total (reduce #'+ sums)))
      (format t "prose words ~D (outside blocks, tables and headings), by kind:~%" total)
      (loop for (nil label) in kinds for s in sums for c in counts
            do (format t "  ~15A ~6D words  ~5,1F %  in ~4D paragraphs~%" label s
                       (if (plusp total) (* 100.0 (/ s total)) 0.0) c))
      (let ((records 0) (record-words 0) (in nil))
        ;; the records tools/mutate.lisp reads live in their own file, off the page
        (when (probe-file *records-file*)
          (loop for line across (lines-of *records-file*)
                for tl = (trim line)
                do (cond ((or (blank-p line) (heading-level line) (starts-with "#" tl)) (setf in nil))
                         ((and (not in) (or (starts-with "Equivalent mutant ~" tl)
                                            (starts-with "Surviving mutant ~" tl)))
                          (setf in t) (incf records) (incf record-words (words tl)))
                         (in (incf record-words (words tl))))))
        (format t "mutant records apart, in ~A: ~D records, ~D words (not the page's prose)~%"
                *records-file* records record-words))
      (format t "tables ~D words, headings ~D words~%" table-words heading-words)
      (format t "sections ~D (~{~A~^, ~}), ~D lines on the page; median section ~D lines, longest ~D~%"
              (length headings)
              (loop for level from 1 to (reduce #'max headings :key #'first)
                    for k = (count level headings :key #'first)
                    when (plusp k) collect (format nil "~D at level ~D" k level))
              (length lines) (round (median lengths)) (reduce #'max lengths))
      (format t "engine blocks ~D (tangled/physics.lisp, tangled/physics-simd.lisp): median ~D lines, ~
                 longest ~D, ~D over 100, ~D over 300~%"
              (length blocks) (round (median blocks)) (reduce #'max blocks)
              (count-if (lambda (b) (> b 100)) blocks) (count-if (lambda (b) (> b 300)) blocks))
      (format t "longest definitions of the tangled engine files (lines, deepest parenthesis):~%")
      (let ((forms (sort (loop for file in '("tangled/physics.lisp" "tangled/physics-simd.lisp")
                               when (probe-file file)
                                 append (mapcar (lambda (f) (append f (list (file-namestring file))))
                                                (forms-of file)))
                         #'> :key #'second)))
        (loop for (name n depth nil file) in forms
              repeat 10
              do (format t "  ~4D lines  depth ~2D  ~A (~A)~%" n depth name file))
        ;; the page's bound on an engine definition: 120 lines, 16 parentheses deep
        (let ((over (remove-if-not (lambda (f) (or (> (second f) 120) (> (third f) 16))) forms)))
          (format t "engine definitions over 120 lines or deeper than 16 parentheses: ~D~%" (length over))
          (loop for (name n depth nil file) in over
                do (format t "  ~4D lines  depth ~2D  ~A (~A)~%" n depth name file))))
      (let ((dump (sb-ext:posix-getenv "PROSE_COUNT_DUMP")))
        (when (and dump (plusp (length dump)))
          (with-open-file (out dump :direction :output :if-exists :supersede :external-format :utf-8)
            (dolist (p paras)
              (format out "~A ~D ~D: ~A~%~%" (para-kind p) (para-start p) (para-words p) (para-text p)))))))))
